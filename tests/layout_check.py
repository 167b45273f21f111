#!/usr/bin/env python3
"""The layout's rules, derived from the sources (docs/layout.md):

  - core/'s folders include one another without a loop: the graph of
    folder -> folder includes (a folder's internal/ counts as the folder;
    core/cli is the command on top of them all) has no cycle;
  - a private header (one in some folder's internal/) is included only by
    the files of that folder (the tests of internals see them through
    their own include path and are not checked here);
  - server/ includes only the core headers on SERVER_ALLOWED: the public
    interfaces of the pipeline, materials, renders and exports, and the
    base utilities, never a numerical stage's own header.

Prints the folder graph and a count (files in core/'s root, folders, the
largest folder), then one line per violation; exits 1 on any.

usage: layout_check.py [SOURCE_ROOT]
"""
import os
import re
import sys

SERVER_ALLOWED = {
    # base
    "buf.h", "cancel.h", "clock.h", "err.h", "fsio.h", "ids.h", "json_text.h", "lru.h", "par.h",
    # images, scenes and environments the daemon stores and checks
    "img.h", "img_raw.h", "mesh.h", "scene.h", "env.h",
    # truths named in requests, the brush the daemon applies
    "merl.h", "measured.h", "stroke.h",
    # the pipeline: methods, precomputations, materials, G-buffer fits
    "method.h", "prep.h", "cache.h", "material.h", "gbfit.h",
    # what leaves: renders, exports, readable summaries
    "render.h", "readable.h", "gltf.h", "mtlx.h", "usda.h", "usdz.h", "brdfx.h", "merl_material.h",
}

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
SOURCE = (".c", ".h", ".cpp")


def folder_of(core, path):
    """The folder of a core file, relative to core/ ('methods/hf'); a file
    in an internal/ belongs to the folder above it."""
    rel = os.path.relpath(os.path.dirname(path), core)
    if os.path.basename(rel) == "internal":
        rel = os.path.dirname(rel)
    return rel


def sources(top):
    for dp, dns, fns in os.walk(top):
        dns[:] = [d for d in dns if not d.startswith(".")]
        for f in fns:
            if f.endswith(SOURCE):
                yield os.path.join(dp, f)


def cycle(graph):
    """One cycle of graph (dict node -> set of nodes) as a list, or None."""
    state, stack = {}, []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(graph.get(n, ())):
            if state.get(m) == 1:
                return stack[stack.index(m):] + [m]
            if m not in state:
                found = visit(m)
                if found:
                    return found
        stack.pop()
        state[n] = 2
        return None

    for n in sorted(graph):
        if n not in state:
            found = visit(n)
            if found:
                return found
    return None


def main():
    src = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                          os.path.join(os.path.dirname(__file__), ".."))
    core = os.path.join(src, "core")
    headers = {}  # basename -> (folder, private)
    files = list(sources(core))
    for p in files:
        if p.endswith(".h"):
            name = os.path.basename(p)
            if name in headers:
                print("FAIL two core headers named %s" % name)
            headers[name] = (folder_of(core, p),
                             os.path.basename(os.path.dirname(p)) == "internal")
    bad = []
    graph, why = {}, {}
    for p in files:
        here = folder_of(core, p)
        for inc in INCLUDE.findall(open(p, errors="replace").read()):
            h = headers.get(os.path.basename(inc))
            if not h:
                continue
            there, private = h
            if private and there != here:
                bad.append("%s includes %s, private to core/%s" % (os.path.relpath(p, src), inc,
                                                                   there))
            if there != here:
                graph.setdefault(here, set()).add(there)
                why.setdefault((here, there), os.path.relpath(p, src) + " -> " + inc)
    loop = cycle(graph)
    if loop:
        bad.append("a loop between core's folders: %s (%s)" % (
            " -> ".join(loop), "; ".join(why[(a, b)] for a, b in zip(loop, loop[1:]))))
    for p in sources(os.path.join(src, "server")):
        for inc in INCLUDE.findall(open(p, errors="replace").read()):
            name = os.path.basename(inc)
            if name in headers and name not in SERVER_ALLOWED:
                bad.append("%s includes %s (core/%s), which is not among the headers the "
                           "daemon may use (SERVER_ALLOWED)" % (os.path.relpath(p, src), inc,
                                                               headers[name][0]))
    # the picture and the count
    for a in sorted(graph):
        print("core/%s -> %s" % (a, ", ".join("core/" + b for b in sorted(graph[a]))))
    per = {}
    for p in files:
        per[folder_of(core, p)] = per.get(folder_of(core, p), 0) + 1
    root_files = per.get(".", 0)
    big = max(per.items(), key=lambda kv: kv[1])
    print("files in core/'s root: %d; folders: %d; the largest: core/%s (%d files)"
          % (root_files, len([k for k in per if k != "."]), big[0], big[1]))
    for b in bad:
        print("FAIL " + b)
    rules = {"loop": any(b.startswith("a loop") for b in bad),
             "private": any("private to" in b for b in bad),
             "server": any("SERVER_ALLOWED" in b for b in bad) or any("two core headers" in b
                                                                       for b in bad)}
    print("%d passed, %d failed" % (sum(not v for v in rules.values()),
                                    sum(v for v in rules.values())))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
