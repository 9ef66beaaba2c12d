#!/usr/bin/env python3
"""check_circles.py: no circles in the library: among the #includes of lib/ and include/, and among the
calls between lib/'s objects (one object uses a global symbol another defines, read with nm).

    python3 tools/check_circles.py SRCDIR [BUILDDIR]

Prints one line per check and each circle found with the includes or symbols that close it; exits 1 when
there is one. Without BUILDDIR (or without objects in it) only the includes are checked. The objects of
lib/libcbvh_test_hooks.la (a second copy of kernel_choice.c, for the tests) are left out."""
import collections
import glob
import os
import re
import subprocess
import sys


def circles(graph):
    """The strongly connected parts of more than one node (Tarjan), each sorted."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            part = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                part.append(w)
                if w == v:
                    break
            if len(part) > 1:
                found.append(sorted(part))

    sys.setrecursionlimit(10000)
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def include_graph(top):
    files = set()
    for folder in ("lib", "include"):
        for d, _, names in os.walk(os.path.join(top, folder)):
            files.update(os.path.relpath(os.path.join(d, n), top) for n in names if n.endswith((".c", ".h")))
    graph = collections.defaultdict(dict)
    for f in sorted(files):
        with open(os.path.join(top, f), errors="replace") as text:
            for line in text:
                m = re.match(r'\s*#\s*include\s+"([^"]+)"', line)
                if not m:
                    continue
                for base in (os.path.dirname(f), "lib", "include"):
                    target = os.path.normpath(os.path.join(base, m.group(1)))
                    if target in files:
                        graph[f][target] = m.group(1)
                        break
    return files, graph


def call_graph(build):
    objects = [o for o in glob.glob(os.path.join(build, "lib", "**", "*.o"), recursive=True)
               if "libcbvh_test_hooks_la-" not in o]
    plain = [o for o in objects if os.sep + ".libs" + os.sep not in o]
    objects = plain or objects  # a shared-only build has its objects in .libs only
    defined, used = {}, {}
    for o in objects:
        name = os.path.relpath(o, build).replace(os.sep + ".libs", "")
        out = subprocess.run(["nm", o], capture_output=True, text=True, check=True).stdout
        for line in out.splitlines():
            parts = line.split()
            if len(parts) == 2 and parts[0] == "U":
                used.setdefault(name, set()).add(parts[1])
            elif len(parts) == 3 and parts[1] in "TDBRCV":
                defined[parts[2]] = name
    graph = collections.defaultdict(dict)
    for user, symbols in used.items():
        for s in sorted(symbols):
            owner = defined.get(s)
            if owner and owner != user:
                graph[user].setdefault(owner, s)
    return objects, graph


def report(what, graph, found):
    for part in found:
        print(f"FAIL {what} circle: {' '.join(part)}")
        for a in part:
            for b, why in sorted(graph[a].items()):
                if b in part:
                    print(f"     | {a} -> {b} ({why})")


def main():
    if len(sys.argv) not in (2, 3):
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    top = sys.argv[1]
    files, graph = include_graph(top)
    found = circles(graph)
    report("include", graph, found)
    if not found:
        print(f"ok   no include circle among the {len(files)} files of lib/ and include/")
    failed = bool(found)
    if len(sys.argv) == 3:
        objects, graph = call_graph(sys.argv[2])
        if objects:
            found = circles(graph)
            report("call", graph, found)
            if not found:
                print(f"ok   no call circle among the {len(objects)} objects of lib/")
            failed = failed or bool(found)
        else:
            print("skip call circles: no library objects in the build folder")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
