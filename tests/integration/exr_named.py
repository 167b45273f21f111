"""OpenEXR files with named channels, written and read without OpenImageIO
(standard library only), for the tests that hand glint G-buffers as another
tool would: scanline files, float/half/uint channels; reads uncompressed,
ZIPS and ZIP (what glint writes), writes uncompressed float.

    chans, w, h = read(data)     # {"N.X": [floats, row-major], ...}
    data = write(w, h, chans)    # channels written in sorted order
"""
import struct
import zlib

_TYPES = {0: ("I", 4), 1: ("e", 2), 2: ("f", 4)}
_LINES = {0: 1, 2: 1, 3: 16}  # none, zips, zip


def _header(data):
    assert data[:4] == b"\x76\x2f\x31\x01", "not an OpenEXR file"
    pos, attrs = 8, {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        tend = data.index(b"\0", end + 1)
        kind = data[end + 1:tend].decode()
        size = struct.unpack_from("<i", data, tend + 1)[0]
        attrs[name] = (kind, data[tend + 5:tend + 5 + size])
        pos = tend + 5 + size
    return attrs, pos + 1


def _channels(body):
    out, pos = [], 0
    while body[pos] != 0:
        end = body.index(b"\0", pos)
        ptype = struct.unpack_from("<i", body, end + 1)[0]
        out.append((body[pos:end].decode(), ptype))
        pos = end + 1 + 16
    return out


def _unzip(raw):
    t = bytearray(zlib.decompress(raw))
    for i in range(1, len(t)):
        t[i] = (t[i - 1] + t[i] - 128) & 0xff
    half, out = (len(t) + 1) // 2, bytearray(len(t))
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return bytes(out)


def read(data):
    attrs, pos = _header(data)
    chans = _channels(attrs["channels"][1])
    comp = attrs["compression"][1][0]
    assert comp in _LINES, "compression %d is not read here" % comp
    x0, y0, x1, y1 = struct.unpack("<iiii", attrs["dataWindow"][1])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    lines = _LINES[comp]
    nblocks = (h + lines - 1) // lines
    offsets = struct.unpack_from("<%dQ" % nblocks, data, pos)
    out = {name: [0.0] * (w * h) for name, _ in chans}
    for off in offsets:
        y, size = struct.unpack_from("<ii", data, off)
        raw = data[off + 8:off + 8 + size]
        n = min(lines, y1 + 1 - y)
        full = sum(_TYPES[t][1] for _, t in chans) * w * n
        if len(raw) < full:
            raw = _unzip(raw)
        p = 0
        for r in range(n):
            for name, t in chans:
                code, sz = _TYPES[t]
                vals = struct.unpack_from("<%d%s" % (w, code), raw, p)
                p += sz * w
                row = (y - y0 + r) * w
                out[name][row:row + w] = [float(v) for v in vals]
    return out, w, h


def write(w, h, chans):
    names = sorted(chans)

    def attr(name, kind, body):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(body)) + body
    chl = b"".join(n.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for n in names) + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2) + attr("channels", "chlist", chl)
              + attr("compression", "compression", b"\0") + attr("dataWindow", "box2i", box)
              + attr("displayWindow", "box2i", box) + attr("lineOrder", "lineOrder", b"\0")
              + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0))
              + attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    blocks = []
    for y in range(h):
        body = b"".join(struct.pack("<%df" % w, *chans[n][y * w:(y + 1) * w]) for n in names)
        blocks.append(struct.pack("<ii", y, len(body)) + body)
    offsets, off = [], len(header) + 8 * h
    for b in blocks:
        offsets.append(off)
        off += len(b)
    return header + struct.pack("<%dQ" % h, *offsets) + b"".join(blocks)
