#!/usr/bin/env python3
"""Checks that every #include points down the layers of docs/design.md ("Layers"): a folder
includes only folders on a lower level (or itself), never one beside or above it, so no folder
cycle can form. Inside core/ and io/ their subfolders are ordered the same way. Prints each
include that breaks the order, with its file and line, and exits 1; exits 0 when there is none.
Run by ctest (Layers.IncludesPointDown) from the source tree: scripts/check_layers.py [ROOT]."""
import os
import re
import sys

# Lowest first; folders on one level do not include each other.
LEVELS = [["core"], ["io"], ["cache"], ["app"], ["serve"], ["mpi"], ["cli"], ["tools", "mpi/cli", "python"]]
# Inside a library folder: (subfolder or "" for the files at its top) -> level.
INNER = {
    "core": {"": 0, "kernel": 1, "mesh_post": 1, "synth": 1, "trees": 2, "view": 3, "lod": 4, "extract": 5},
    "io": {"": 0, "remote": 1, "render": 1, "readers": 2, "store": 3, "mesh": 3},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def folder_of(path):
    """The layer folder of a repository path ('mpi/cli' apart from 'mpi'), or None."""
    parts = path.split("/")
    if parts[:2] == ["mpi", "cli"]:
        return "mpi/cli"
    return parts[0] if len(parts) > 1 else None


def level_of(folder):
    for level, folders in enumerate(LEVELS):
        if folder in folders:
            return level
    return None


def inner_of(path):
    """(library, subfolder) for a path inside core/ or io/: the subfolder '' at its top."""
    parts = path.split("/")
    if parts[0] not in INNER or len(parts) < 2:
        return None
    return parts[0], parts[1] if len(parts) > 2 else ""


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    problems = []
    for top in sorted({f for level in LEVELS for f in level if "/" not in f}):
        for directory, _, files in os.walk(os.path.join(root, top)):
            for name in sorted(files):
                if not name.endswith((".h", ".cpp")):
                    continue
                path = os.path.relpath(os.path.join(directory, name), root).replace(os.sep, "/")
                mine = folder_of(path)
                with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
                    lines = f.readlines()
                for number, line in enumerate(lines, 1):
                    m = INCLUDE.match(line)
                    if not m or not os.path.exists(os.path.join(root, m.group(1))):
                        continue  # a system header, or one beside the file
                    target = m.group(1)
                    theirs = folder_of(target)
                    where = f"{path}:{number}: includes {target}"
                    if level_of(theirs) is None:
                        if theirs not in ("tests", "bench", "fuzz"):
                            problems.append(f"{where}: {theirs}/ is in no layer (add it to scripts/check_layers.py and docs/design.md)")
                        else:
                            problems.append(f"{where}: a library includes {theirs}/")
                        continue
                    if theirs != mine:
                        if level_of(theirs) >= level_of(mine):
                            problems.append(f"{where}: {mine}/ may include only layers below it, and {theirs}/ is not")
                        continue
                    a, b = inner_of(path), inner_of(target)
                    if not a or not b or a[1] == b[1]:
                        continue
                    levels = INNER[a[0]]
                    if a[1] not in levels or b[1] not in levels:
                        unknown = a[1] if a[1] not in levels else b[1]
                        problems.append(f"{where}: {a[0]}/{unknown}/ is in no layer (add it to scripts/check_layers.py)")
                    elif levels[b[1]] >= levels[a[1]]:
                        problems.append(f"{where}: in {a[0]}/, {a[1] or 'the top'} may include only subfolders below it")
    for p in problems:
        print(p)
    if problems:
        print(f"check_layers: {len(problems)} include(s) against the layers of docs/design.md")
        return 1
    print("check_layers: every include points down the layers")
    return 0


if __name__ == "__main__":
    sys.exit(main())
