"""Checks of glint's MaterialX (.mtlx), USD (.usda) and USDZ (.usdz)
exports against the node definitions of their specifications (no MaterialX
or USD reader is packaged where the tests run).

The tables below are copied from the specifications' own node definitions:
  - MaterialX, libraries/bxdf/standard_surface.mtlx (nodedef
    ND_standard_surface_surfaceshader_100, which ND_standard_surface_surfaceshader
    1.0.1 inherits) and libraries/stdlib/stdlib_defs.mtlx (ND_surfacematerial,
    ND_image_<type>, ND_extract_<type>), AcademySoftwareFoundation/MaterialX at
    4177b2cbd48b579ca1e8f7d9901584d811c63b68;
  - UsdPreviewSurface, UsdUVTexture and UsdPrimvarReader_float2,
    pxr/usdImaging/plugin/usdShaders/shaders/shaderDefs.usda (their def
    Shader blocks), PixarAnimationStudios/OpenUSD at
    59992d2178afcebd89273759f2bddfe730e59aa8, and the UsdGeomMesh / UsdGeomPointBased
    attribute types of pxr/usd/usdGeom/schema.usda there.

What is checked: every input's name and type against the table, each value
parses as its type and lies in the definition's range (uimin..uimax; for USD
the documented range: metallic, roughness [0, 1], colours [0, 1] for a fitted
albedo, ior > 0; the metallic workflow, or the specular one with its
specularColor), the shader is connected as the specification says
(surfacematerial.surfaceshader names the standard_surface node; the
Material's outputs:surface connects to the shader's outputs:surface), every
file an input names exists next to the export (or in its package), and for USD the mesh's arrays agree (3 indices per face,
indices in range, one normal and st per point).  A texture reader's inputs
and outputs against its definition too, and every connection names an
output of a shader of the Material.  A USDZ package (the "Usdz File Format
Specification" of OpenUSD's documentation): a zip whose files are stored
(not compressed), each one's data at a multiple of 64 bytes, the first a
USD layer, which is then checked as above with the files it names looked
up in the package (PNG images).  A MaterialX package (.mtlx.zip, as
three.js's MaterialXLoader reads it): a zip whose first file is the document, checked as above with the files it
names looked up in the package; a standard_surface input connected to a
nodegraph names one of its outputs, of the input's type, and the graph's
image and extract nodes are checked against their definitions (input
names and types, the address modes' enum, extract's index within
uimin..uimax, each connection to a node of the graph of the type the
input has).

usage: export_specs.py mtlx|mtlx.zip|usda|usdz FILE   (exit status 0 when it conforms)
"""
import math
import os
import re
import struct
import sys
import xml.etree.ElementTree as ET
import zipfile

# name: (type, min, max) of ND_standard_surface_surfaceshader_100 (uimin, uimax;
# uisoftmin/uisoftmax where only those are given: not a hard range, so None).
STANDARD_SURFACE = {
    "base": ("float", 0.0, 1.0), "base_color": ("color3", 0.0, 1.0),
    "diffuse_roughness": ("float", 0.0, 1.0), "metalness": ("float", 0.0, 1.0),
    "specular": ("float", 0.0, 1.0), "specular_color": ("color3", 0.0, 1.0),
    "specular_roughness": ("float", 0.0, 1.0), "specular_IOR": ("float", 0.0, None),
    "specular_anisotropy": ("float", 0.0, 1.0), "specular_rotation": ("float", 0.0, 1.0),
    "transmission": ("float", 0.0, 1.0), "transmission_color": ("color3", 0.0, 1.0),
    "transmission_depth": ("float", 0.0, None), "transmission_scatter": ("color3", 0.0, 1.0),
    "transmission_scatter_anisotropy": ("float", 0.0, 1.0),
    "transmission_dispersion": ("float", 0.0, None),
    "transmission_extra_roughness": ("float", -1.0, 1.0), "subsurface": ("float", 0.0, 1.0),
    "subsurface_color": ("color3", 0.0, 1.0), "subsurface_radius": ("color3", 0.0, 1.0),
    "subsurface_scale": ("float", 0.0, None), "subsurface_anisotropy": ("float", -1.0, 1.0),
    "sheen": ("float", 0.0, 1.0), "sheen_color": ("color3", 0.0, 1.0),
    "sheen_roughness": ("float", 0.0, 1.0), "coat": ("float", 0.0, 1.0),
    "coat_color": ("color3", 0.0, 1.0), "coat_roughness": ("float", 0.0, 1.0),
    "coat_anisotropy": ("float", 0.0, 1.0), "coat_rotation": ("float", 0.0, 1.0),
    "coat_IOR": ("float", 0.0, None), "coat_normal": ("vector3", None, None),
    "coat_affect_color": ("float", 0.0, 1.0), "coat_affect_roughness": ("float", 0.0, 1.0),
    "thin_film_thickness": ("float", 0.0, None), "thin_film_IOR": ("float", 0.0, None),
    "emission": ("float", 0.0, None), "emission_color": ("color3", 0.0, 1.0),
    "opacity": ("color3", 0.0, 1.0), "thin_walled": ("boolean", None, None),
    "normal": ("vector3", None, None), "tangent": ("vector3", None, None),
}
STANDARD_SURFACE_OUTPUT = "surfaceshader"
# ND_surfacematerial (stdlib_defs.mtlx): its inputs and its output type.
SURFACEMATERIAL = {"surfaceshader": "surfaceshader", "backsurfaceshader": "surfaceshader",
                   "displacementshader": "displacementshader"}
SURFACEMATERIAL_OUTPUT = "material"
# ND_image_<type> (stdlib_defs.mtlx): its inputs, "default" of the node's own type.
IMAGE_INPUTS = {"file": "filename", "layer": "string", "default": None, "texcoord": "vector2",
                "uaddressmode": "string", "vaddressmode": "string", "filtertype": "string",
                "framerange": "string", "frameoffset": "integer", "frameendaction": "string"}
IMAGE_TYPES = {"float", "color3", "color4", "vector2", "vector3", "vector4"}
IMAGE_ENUMS = {"uaddressmode": {"constant", "clamp", "periodic", "mirror"},
               "vaddressmode": {"constant", "clamp", "periodic", "mirror"},
               "filtertype": {"closest", "linear", "cubic"},
               "frameendaction": {"constant", "clamp", "periodic", "mirror"}}
# ND_extract_<type>: the type of its "in" and the uimax of its "index" (uimin 0); out float.
EXTRACT_IN = {"color3": 2, "color4": 3, "vector2": 1, "vector3": 2, "vector4": 3}
# What glint writes: the inputs that carry the fit (the rest keep their defaults).
MTLX_FIT_INPUTS = {"base_color", "metalness", "specular_roughness", "specular_IOR"}

# UsdPreviewSurface inputs (shaderDefs.usda): name: (USD type, min, max).
PREVIEW_SURFACE = {
    "diffuseColor": ("color3f", 0.0, 1.0), "emissiveColor": ("color3f", 0.0, None),
    "useSpecularWorkflow": ("int", 0, 1), "specularColor": ("color3f", 0.0, 1.0),
    "metallic": ("float", 0.0, 1.0), "roughness": ("float", 0.0, 1.0),
    "clearcoat": ("float", 0.0, 1.0), "clearcoatRoughness": ("float", 0.0, 1.0),
    "opacity": ("float", 0.0, 1.0), "opacityThreshold": ("float", 0.0, 1.0),
    "ior": ("float", 1e-6, None), "normal": ("normal3f", -1.0, 1.0),
    "displacement": ("float", None, None), "occlusion": ("float", 0.0, 1.0),
}
PREVIEW_SURFACE_OUTPUTS = {"surface": "token", "displacement": "token"}
# UsdUVTexture (shaderDefs.usda): inputs name: (type, allowed tokens or None).
UV_TEXTURE = {
    "file": ("asset", None), "st": ("float2", None),
    "wrapS": ("token", {"black", "clamp", "repeat", "mirror", "useMetadata"}),
    "wrapT": ("token", {"black", "clamp", "repeat", "mirror", "useMetadata"}),
    "fallback": ("float4", None), "scale": ("float4", None), "bias": ("float4", None),
    "sourceColorSpace": ("token", {"raw", "sRGB", "auto"}),
}
UV_TEXTURE_OUTPUTS = {"r": "float", "g": "float", "b": "float", "a": "float", "rgb": "float3"}
# UsdPrimvarReader_float2 (shaderDefs.usda)
PRIMVAR_READER_FLOAT2 = {"varname": ("string", None), "fallback": ("float2", None)}
PRIMVAR_READER_FLOAT2_OUTPUTS = {"result": "float2"}
# what a connection may feed: an input's type from an output's (USD connects
# float3 to color3f: both are three floats)
FEEDS = {"color3f": {"float3", "color3f"}, "float": {"float"}, "float2": {"float2"}}
USD_FIT_INPUTS = {"diffuseColor", "metallic", "roughness", "useSpecularWorkflow", "ior"}
# UsdGeomMesh / UsdGeomPointBased attributes glint writes, with their schema types.
USD_MESH_ATTRS = {
    "faceVertexCounts": "int[]", "faceVertexIndices": "int[]", "points": "point3f[]",
    "normals": "normal3f[]", "primvars:st": "texCoord2f[]", "subdivisionScheme": "token",
    "orientation": "token",
}
COMPONENTS = {"float": 1, "int": 1, "color3": 3, "vector3": 3, "color3f": 3, "normal3f": 3}


class Bad(Exception):
    pass


def need(cond, msg):
    if not cond:
        raise Bad(msg)


def in_range(name, vals, lo, hi):
    for v in vals:
        need(math.isfinite(v), "%s: %r is not finite" % (name, v))
        need(lo is None or v >= lo, "%s: %r below %r" % (name, v, lo))
        need(hi is None or v <= hi, "%s: %r above %r" % (name, v, hi))


def check_files(path, names):
    """Every file an export names exists next to it."""
    base = os.path.dirname(os.path.abspath(path))
    for n in names:
        need(os.path.exists(os.path.join(base, n)), "names a file not in the export: %s" % n)


def check_graph(g):
    """A nodegraph's image, extract and output elements against their node
    definitions; returns ({output name: type}, [file names])."""
    nodes, outputs, files = {}, {}, []
    for el in g:
        n = el.get("name")
        need(n and n not in nodes and n not in outputs, "nodegraph %s: a missing or repeated name" % g.get("name"))
        if el.tag == "output":
            outputs[n] = el
        else:
            nodes[n] = el
    for n, el in nodes.items():
        t = el.get("type")
        if el.tag == "image":
            need(t in IMAGE_TYPES, "image %s of type %s has no nodedef" % (n, t))
            ins = {}
            for inp in el.findall("input"):
                k, it = inp.get("name"), inp.get("type")
                need(k in IMAGE_INPUTS, "image has no input %r" % k)
                need(it == (IMAGE_INPUTS[k] or t), "image.%s is %s in the nodedef, %s here" % (k, IMAGE_INPUTS[k] or t, it))
                if k in IMAGE_ENUMS:
                    need(inp.get("value") in IMAGE_ENUMS[k], "image.%s: %r is not one of %s" % (k, inp.get("value"), sorted(IMAGE_ENUMS[k])))
                ins[k] = inp
            need("file" in ins and ins["file"].get("value"), "image %s reads no file" % n)
            files.append(ins["file"].get("value"))
        elif el.tag == "extract":
            need(t == "float", "extract %s is %s, not float" % (n, t))
            ins = {inp.get("name"): inp for inp in el.findall("input")}
            need(set(ins) <= {"in", "index"} and "in" in ins, "extract %s: inputs %s" % (n, sorted(ins)))
            it = ins["in"].get("type")
            need(it in EXTRACT_IN, "extract has no nodedef for an input of type %s" % it)
            src = nodes.get(ins["in"].get("nodename"))
            need(src is not None and src.get("type") == it,
                 "extract %s reads %r, not a %s node of the graph" % (n, ins["in"].get("nodename"), it))
            if "index" in ins:
                need(ins["index"].get("type") == "integer", "extract.index is integer in the nodedef")
                k = int(ins["index"].get("value"))
                need(0 <= k <= EXTRACT_IN[it], "extract.index %d outside 0..%d" % (k, EXTRACT_IN[it]))
        else:
            need(False, "nodegraph %s holds a %s node, which these checks do not know" % (g.get("name"), el.tag))
    for n, el in outputs.items():
        src = nodes.get(el.get("nodename"))
        need(src is not None, "output %s names no node of the graph" % n)
        need(el.get("type") == src.get("type"), "output %s is %s, its node %s" % (n, el.get("type"), src.get("type")))
    return {n: el.get("type") for n, el in outputs.items()}, files


def check_mtlx(text, path=None, in_package=None):
    """The MaterialX document's nodes against the node definitions; returns
    {input: value} of the standard_surface (a connected input: "<graph>.<output>")."""
    root = ET.fromstring(text)
    need(root.tag == "materialx", "root element is %s, not materialx" % root.tag)
    need(re.fullmatch(r"1\.3[89]", root.get("version", "")), "materialx version %r" % root.get("version"))
    surfs = root.findall("standard_surface")
    mats = root.findall("surfacematerial")
    need(len(surfs) == 1 and len(mats) == 1, "one standard_surface and one surfacematerial")
    s, m = surfs[0], mats[0]
    need(s.get("type") == STANDARD_SURFACE_OUTPUT, "standard_surface type %r" % s.get("type"))
    need(m.get("type") == SURFACEMATERIAL_OUTPUT, "surfacematerial type %r" % m.get("type"))
    values, files, graphs = {}, [], {}
    for g in root.findall("nodegraph"):
        outs, gf = check_graph(g)
        graphs[g.get("name")] = outs
        files += gf
    for inp in s.findall("input"):
        n, t = inp.get("name"), inp.get("type")
        need(n in STANDARD_SURFACE, "standard_surface has no input %r" % n)
        want, lo, hi = STANDARD_SURFACE[n]
        need(t == want, "%s is %s in the nodedef, %s here" % (n, want, t))
        need(n not in values, "input %s given twice" % n)
        if inp.get("nodegraph"):
            g, o = inp.get("nodegraph"), inp.get("output")
            need(g in graphs and o in graphs[g], "%s names %s.%s, which does not exist" % (n, g, o))
            need(graphs[g][o] == t, "%s (%s) is fed a %s" % (n, t, graphs[g][o]))
            values[n] = "%s.%s" % (g, o)
            continue
        need(not inp.get("nodename"), "%s names a node outside a nodegraph" % n)
        if t == "filename":
            files.append(inp.get("value"))
            continue
        vals = [float(x) for x in inp.get("value", "").split(",")]
        need(len(vals) == COMPONENTS[t], "%s: %d components for %s" % (n, len(vals), t))
        in_range(n, vals, lo, hi)
        values[n] = vals if len(vals) > 1 else vals[0]
    need(MTLX_FIT_INPUTS <= set(values), "missing %s" % (MTLX_FIT_INPUTS - set(values)))
    for inp in m.findall("input"):
        n, t = inp.get("name"), inp.get("type")
        need(n in SURFACEMATERIAL and SURFACEMATERIAL[n] == t, "surfacematerial input %s %s" % (n, t))
    conn = [i for i in m.findall("input") if i.get("name") == "surfaceshader"]
    need(len(conn) == 1 and conn[0].get("nodename") == s.get("name"),
         "surfacematerial.surfaceshader does not name the standard_surface")
    for img in root.iter("image"):
        for inp in img.findall("input"):
            if inp.get("type") == "filename" and inp.get("value") not in files:
                files.append(inp.get("value"))
    if in_package:
        in_package(files)
    elif path:
        check_files(path, files)
    return values


def open_package(path, first, usdz):
    """A zip's layout (the CRCs right, nothing encrypted, the first file's
    name ending in one of `first`; for USDZ every file stored and its data
    64-byte aligned); returns (ZipFile, infos, in_package: the check that
    the files a document names are PNG images in the package)."""
    with open(path, "rb") as f:
        raw = f.read()
    z = zipfile.ZipFile(path)
    infos = z.infolist()
    need(infos and infos[0].filename.endswith(first), "the package does not start with a %s file" % "/".join(first))
    for i in infos:
        need(not i.flag_bits & 1, "%s is encrypted" % i.filename)
        if not usdz:
            continue
        need(i.compress_type == zipfile.ZIP_STORED, "%s is compressed" % i.filename)
        h = i.header_offset
        need(raw[h:h + 4] == b"PK\x03\x04", "no local header for %s" % i.filename)
        nl, el = struct.unpack("<HH", raw[h + 26:h + 30])
        need((h + 30 + nl + el) % 64 == 0, "%s's data is not 64-byte aligned" % i.filename)
    need(z.testzip() is None, "a file's CRC does not match")
    names = set(z.namelist())

    def in_package(files):
        for n in files:
            need(n in names, "names a file not in the package: %s" % n)
            need(z.read(n)[:8] == b"\x89PNG\r\n\x1a\n", "%s is not a PNG image" % n)
    return z, infos, in_package


def check_mtlx_zip(path):
    """The MaterialX package: its layout, then its document with the files
    it names in it; returns (values, sorted names)."""
    z, infos, in_package = open_package(path, (".mtlx",), False)
    values = check_mtlx(z.read(infos[0].filename).decode("utf-8"), in_package=in_package)
    return values, sorted(z.namelist())


def usd_prims(text):
    """The layer's prims: [(kind, name, metadata, body text)] by brace matching
    (a small parser for what glint writes: def blocks, attributes one per line)."""
    prims, i = [], 0
    for m in re.finditer(r'def (\w+) "(\w+)"', text):
        j = text.index("{", m.end())
        depth, k = 0, j
        while True:
            depth += {"{": 1, "}": -1}.get(text[k], 0)
            if depth == 0:
                break
            k += 1
        prims.append((m.group(1), m.group(2), text[m.end():j], text[j + 1:k]))
    return prims


def own_lines(body):
    """The lines of a prim's body outside its child prims."""
    out, depth = [], 0
    for line in body.splitlines():
        if depth == 0 and not line.strip().startswith("def "):
            out.append(line.strip())
        depth += line.count("{") - line.count("}")
    return out


def parse_tuple_values(s):
    return [float(x) for x in re.findall(r"[-+0-9.eE]+", s)]


def check_usda(text, path=None):
    """The layer's shader and mesh against the specification; returns
    {input: value} of the UsdPreviewSurface."""
    need(text.startswith("#usda 1.0"), "not a text USD layer")
    need(re.search(r'defaultPrim = "glint"', text), "no defaultPrim")
    need(re.search(r'upAxis = "Z"', text), "upAxis is not Z")
    prims = {name: (kind, body) for kind, name, _, body in usd_prims(text)}
    meta = {name: md for _, name, md, _ in usd_prims(text)}
    shaders = {n: b for n, (k, b) in prims.items() if k == "Shader"}
    mats = [(n, b) for n, (k, b) in prims.items() if k == "Material"]
    surfaces = [n for n, b in shaders.items() if 'uniform token info:id = "UsdPreviewSurface"' in b]
    need(len(surfaces) == 1 and len(mats) == 1, "one Material and one UsdPreviewSurface")
    sname, sbody = surfaces[0], shaders[surfaces[0]]
    mname, mbody = mats[0]
    outputs = {}     # shader name: {output: type}
    for n, b in shaders.items():
        if n != sname:
            outputs[n] = check_reader(n, b)
    outputs[sname] = {}
    values, files = {}, []
    for line in own_lines(sbody):
        m = re.match(r"(\w+) inputs:(\w+)\.connect = <(/[\w/]+)\.outputs:(\w+)>$", line)
        if m:
            t, n, target, out = m.groups()
            need(n in PREVIEW_SURFACE, "UsdPreviewSurface has no input %r" % n)
            need(t == PREVIEW_SURFACE[n][0], "%s is %s in shaderDefs.usda, %s here" % (n, PREVIEW_SURFACE[n][0], t))
            src = target.rsplit("/", 1)[-1]
            need(target == "/glint/%s/%s" % (mname, src) and src in outputs and out in outputs[src],
                 "%s connects to %s.outputs:%s, no output of the Material's shaders" % (n, target, out))
            need(outputs[src][out] in FEEDS.get(t, {t}), "%s (%s) fed by a %s" % (n, t, outputs[src][out]))
            values[n] = "connected"
            continue
        m = re.match(r"(\w+) inputs:(\w+) = (.+)$", line)
        if m:
            t, n, v = m.groups()
            need(n in PREVIEW_SURFACE, "UsdPreviewSurface has no input %r" % n)
            want, lo, hi = PREVIEW_SURFACE[n]
            need(t == want, "%s is %s in shaderDefs.usda, %s here" % (n, want, t))
            vals = parse_tuple_values(v)
            need(len(vals) == COMPONENTS[t], "%s: %d components for %s" % (n, len(vals), t))
            if t == "int":
                need(re.fullmatch(r"-?\d+", v.strip()), "%s: %r is not an int" % (n, v))
            in_range(n, vals, lo, hi)
            values[n] = vals if len(vals) > 1 else vals[0]
            continue
        m = re.match(r"(\w+) outputs:(\w+)$", line)
        if m:
            need(PREVIEW_SURFACE_OUTPUTS.get(m.group(2)) == m.group(1), "output %s" % line)
    need(USD_FIT_INPUTS <= set(values), "missing %s" % (USD_FIT_INPUTS - set(values)))
    # the metallic workflow, or (a pbr material's dielectric with
    # KHR_materials_specular) the specular one with its specularColor
    need(values["useSpecularWorkflow"] == 0 or "specularColor" in values,
         "the specular workflow without a specularColor")
    need(re.search(r"token outputs:surface\.connect = </glint/%s/%s\.outputs:surface>" % (mname, sname), mbody),
         "the Material's surface does not connect to the shader")
    meshes = [(n, b) for n, (k, b) in prims.items() if k == "Mesh"]
    for n, body in meshes:
        check_usd_mesh(body, meta[n], mname)
    for m in re.finditer(r"@([^@]+)@", text):
        files.append(m.group(1))
    if callable(path):
        path(files)
    elif path:
        check_files(path, files)
    return values, len(meshes)


def check_reader(name, body):
    """A texture reader of the Material (UsdUVTexture, UsdPrimvarReader_float2)
    against its definition; returns its outputs {name: type}."""
    m = re.search(r'uniform token info:id = "(\w+)"', body)
    need(m, "shader %s has no info:id" % name)
    kind = m.group(1)
    defs = {"UsdUVTexture": (UV_TEXTURE, UV_TEXTURE_OUTPUTS),
            "UsdPrimvarReader_float2": (PRIMVAR_READER_FLOAT2, PRIMVAR_READER_FLOAT2_OUTPUTS)}
    need(kind in defs, "shader %s is a %s, not a UsdPreviewSurface's reader" % (name, kind))
    inputs, outs = defs[kind]
    found = {}
    for line in own_lines(body):
        m = re.match(r"(\w+) inputs:(\w+)(\.connect)? = (.+)$", line)
        if m:
            t, n, conn, v = m.groups()
            need(n in inputs, "%s has no input %r" % (kind, n))
            need(t == inputs[n][0], "%s.%s is %s in shaderDefs.usda, %s here" % (kind, n, inputs[n][0], t))
            if inputs[n][1] is not None:
                need(v.strip('"') in inputs[n][1], "%s.%s: %s is not one of %s" % (kind, n, v, sorted(inputs[n][1])))
            found[n] = v
            continue
        m = re.match(r"(\w+) outputs:(\w+)$", line)
        if m:
            need(outs.get(m.group(2)) == m.group(1), "%s has no output %s" % (kind, line))
            found["outputs:" + m.group(2)] = m.group(1)
    if kind == "UsdUVTexture":
        need("file" in found and "st" in found, "%s reads no file at no st" % name)
    else:
        need(found.get("varname") == '"st"', "%s reads %s, not st" % (name, found.get("varname")))
    return {k[8:]: v for k, v in found.items() if k.startswith("outputs:")}


def check_usdz(path):
    """The package's layout, then its layer with the files it names in it."""
    z, infos, in_package = open_package(path, (".usda", ".usdc"), True)
    layer = z.read(infos[0].filename).decode("utf-8")
    values, meshes = check_usda(layer, in_package)
    return values, meshes, sorted(z.namelist())


def check_usd_mesh(body, meta, mname):
    attrs = {}
    for line in own_lines(body):
        m = re.match(r"(?:uniform )?([\w\[\]]+) ([\w:]+) = (.+?)(?: \($)?$", line)
        if m and m.group(2) in USD_MESH_ATTRS:
            need(m.group(1) == USD_MESH_ATTRS[m.group(2)], "%s is %s, not %s" % (m.group(2), m.group(1), USD_MESH_ATTRS[m.group(2)]))
            attrs[m.group(2)] = m.group(3)
    for a in ("faceVertexCounts", "faceVertexIndices", "points", "normals"):
        need(a in attrs, "the mesh has no %s" % a)
    counts = [int(x) for x in re.findall(r"-?\d+", attrs["faceVertexCounts"])]
    idx = [int(x) for x in re.findall(r"-?\d+", attrs["faceVertexIndices"])]
    pts = parse_tuple_values(attrs["points"])
    nrm = parse_tuple_values(attrs["normals"])
    need(len(pts) % 3 == 0 and len(pts) >= 9, "points are not triples")
    np_ = len(pts) // 3
    need(sum(counts) == len(idx) and all(c == 3 for c in counts), "faces and indices disagree")
    need(min(idx) >= 0 and max(idx) < np_, "an index outside the points")
    need(len(nrm) == 3 * np_, "one normal per point (interpolation vertex)")
    for k in range(np_):
        ln = math.sqrt(sum(nrm[3 * k + e] ** 2 for e in range(3)))
        need(abs(ln - 1.0) < 1e-3, "normal %d has length %g" % (k, ln))
    if "primvars:st" in attrs:
        st = parse_tuple_values(attrs["primvars:st"])
        need(len(st) == 2 * np_, "one st per point")
        in_range("st", st, 0.0, 1.0)
    need(re.search(r"rel material:binding = </glint/%s>" % mname, body), "the mesh is not bound to the Material")
    need(re.search(r'apiSchemas = \[[^]]*"MaterialBindingAPI"', meta), "the mesh does not apply MaterialBindingAPI")


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("mtlx", "mtlx.zip", "usda", "usdz"):
        sys.exit("usage: export_specs.py mtlx|mtlx.zip|usda|usdz FILE")
    try:
        if sys.argv[1] in ("usdz", "mtlx.zip"):
            print(check_usdz(sys.argv[2]) if sys.argv[1] == "usdz" else check_mtlx_zip(sys.argv[2]))
            sys.exit(0)
        with open(sys.argv[2], encoding="utf-8") as f:
            t = f.read()
        print(check_mtlx(t, sys.argv[2]) if sys.argv[1] == "mtlx" else check_usda(t, sys.argv[2]))
    except (Bad, ET.ParseError, ValueError, KeyError, zipfile.BadZipFile) as e:
        sys.exit("%s: %s" % (sys.argv[2], e))
