"""Files and strokes of the memory probes (test_probe_memory.py and
tests/bench/bench_memory.py): images whose header declares a size, made
in a moment however large, and strokes whose points lie far outside the
image.  Standard library only.
"""
import struct
import zlib


def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png_declaring(w, h, depth=8):
    """A well-formed w x h RGB PNG (8 or 16 bits), black: rows of zeros
    deflate to a thousandth of their size.  Made from one compressed chunk
    of rows repeated (each ends with a full flush, so none refers to
    another), which takes a moment where deflating every row took seconds."""
    row = b"\0" * (1 + 3 * w * depth // 8)
    rows = 64 if h % 64 == 0 else h
    z = zlib.compressobj(9, zlib.DEFLATED, -15)
    block = z.compress(row * rows) + z.flush(zlib.Z_FULL_FLUSH)
    adler = 1
    for _ in range(h // rows):
        adler = zlib.adler32(row * rows, adler)
    idat = b"\x78\xda" + block * (h // rows) + b"\x03\x00" + struct.pack(">I", adler)
    ihdr = struct.pack(">IIBBBBB", w, h, depth, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", ihdr) + png_chunk(b"IDAT", idat) +
            png_chunk(b"IEND", b""))


def _exr_attr(name, kind, value):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def exr_declaring(w, h, names, half=False):
    """A w x h scanline OpenEXR file of float (or half) channels `names`
    (sorted), ZIP-compressed, every value 0: each block of 16 lines
    deflates to a few KB, and every block is the same but the last."""
    names = sorted(names)
    ptype, size = (1, 2) if half else (2, 4)
    chlist = b"".join(n.encode() + b"\0" + struct.pack("<iBBBBii", ptype, 0, 0, 0, 0, 1, 1)
                      for n in names) + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    head = struct.pack("<ii", 20000630, 2)
    head += _exr_attr("channels", "chlist", chlist)
    head += _exr_attr("compression", "compression", b"\x03")
    head += _exr_attr("dataWindow", "box2i", box)
    head += _exr_attr("displayWindow", "box2i", box)
    head += _exr_attr("lineOrder", "lineOrder", b"\0")
    head += _exr_attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
    head += _exr_attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
    head += _exr_attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0"

    def packed(lines):  # zeros, split and differenced: a 0, then 128s
        n = lines * w * len(names) * size
        return zlib.compress(b"\0" + b"\x80" * (n - 1), 9)

    nblocks = (h + 15) // 16
    full = packed(16)
    last = packed(h - 16 * (nblocks - 1))
    offsets, blocks, at = [], [], len(head) + 8 * nblocks
    for b in range(nblocks):
        data = full if b < nblocks - 1 else last
        blocks.append(struct.pack("<ii", 16 * b, len(data)) + data)
        offsets.append(at)
        at += len(blocks[-1])
    return head + struct.pack("<%dQ" % nblocks, *offsets) + b"".join(blocks)


def far_stroke(npoints):
    """A stroke of npoints points, its first inside a 32x32 image and the
    others far outside it: it costs next to no brush work, and its JSON
    is long."""
    pts = [[16, 16]] + [[-500000 - i, -700000 - i] for i in range(npoints - 1)]
    return {"color": [0.5, 0.5, 0.5], "diameter": 1, "points": pts}




def hdr_flat(w, h):
    """A w x h Radiance HDR file, black, its scanlines flat (not run-length
    encoded): 4 bytes a pixel."""
    return b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w) + bytes(4 * w * h)
