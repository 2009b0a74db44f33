#!/usr/bin/env python3
"""Checks that the rooms (source folders) depend on each other in one direction only.

Each room has a floor; a source file may include headers of its own room and of rooms on lower
floors, never of its own floor's other rooms or of higher floors. Usage:
  check_layers.py ROOT          check the tree at ROOT (exit 1 and one line per upward include)
  check_layers.py --self-test   check that an upward and a sideways include are caught
"""
import pathlib
import re
import sys

# Floor of each room, ground floor first. Tests, benchmarks and fuzz targets may use every room.
FLOORS = {
    "basics": 0,
    "numerics": 1, "estimation": 1,
    "muscles": 2,
    "model": 3,
    "experiments": 4, "render": 4,
    "identification": 5,
    "studies": 6,
    "cli": 7, "python": 7,
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/[^"]+"', re.M)
SOURCES = (".h", ".hpp", ".cpp", ".cc")


def find_violations(files):
    """files: {relative path: text}. Returns the upward or sideways includes as messages."""
    out = []
    for path, text in sorted(files.items()):
        room = path.split("/")[0]
        if room not in FLOORS:
            continue
        for lineno, line in enumerate(text.splitlines(), 1):
            m = INCLUDE.match(line)
            if not m or m.group(1) == room or m.group(1) not in FLOORS:
                continue
            target = m.group(1)
            if FLOORS[target] >= FLOORS[room]:
                how = "up" if FLOORS[target] > FLOORS[room] else "sideways"
                out.append(f"{path}:{lineno}: {room} (floor {FLOORS[room]}) includes {target} "
                           f"(floor {FLOORS[target]}): a dependency {how}")
    return out


def read_tree(root):
    files = {}
    for room in FLOORS:
        for p in (root / room).rglob("*"):
            if p.suffix in SOURCES and p.is_file():
                files[p.relative_to(root).as_posix()] = p.read_text(errors="replace")
    return files


def self_test():
    files = {
        "muscles/a.cpp": '#include "basics/errors.h"\n#include "model/arm.h"\n',
        "render/b.cpp": '#include "experiments/emg.h"\n',
        "studies/c.cpp": '#include "identification/identifier.h"\n',
    }
    v = find_violations(files)
    ok = len(v) == 2 and "muscles/a.cpp:2" in v[0] and "sideways" in v[1]
    print("self-test:", "caught both" if ok else f"FAILED: {v}")
    return 0 if ok else 1


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    root = pathlib.Path(argv[1])
    files = read_tree(root)
    missing = [r for r in FLOORS if not (root / r).is_dir()]
    if missing:
        print(f"check_layers: rooms missing under {root}: {', '.join(missing)}", file=sys.stderr)
        return 1
    violations = find_violations(files)
    for v in violations:
        print(v)
    lines = {}
    for path, text in files.items():
        lines[path.split("/")[0]] = lines.get(path.split("/")[0], 0) + text.count("\n")
    print("rooms (lines):", ", ".join(f"{r} {lines.get(r, 0)}" for r in FLOORS))
    print(f"{len(files)} files, {len(violations)} upward or sideways includes")
    return 1 if violations else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
