#!/usr/bin/env python3
"""Checks that no function of the library rooms is longer than 100 lines, binding tables excepted.

A function is a definition starting at column 0 (a signature of up to 8 lines ending in "{") through
its matching "}". Binding tables (the Python module's and the command's option registrations: names
in TABLES) may be longer. Usage:
  check_function_length.py ROOT          check the tree at ROOT (exit 1 and one line per long function)
  check_function_length.py --self-test   check that a long function is caught and a table is not
"""
import pathlib
import re
import sys

LIMIT = 100
ROOMS = ("basics", "numerics", "estimation", "muscles", "model", "experiments", "render", "identification",
         "studies", "cli", "python")
# Tables that bind functions to names (pybind11 definitions, CLI11 option registrations).
TABLES = re.compile(r"^(PYBIND11_MODULE\(|void add\w*(Bindings|Commands)\()")
START = re.compile(r"^[A-Za-z_].*\(")
SKIP = ("namespace", "struct", "class", "enum", "union", "using", "static_assert", "template", "typedef", "}", "#")


def find_long_functions(path, text):
    """Returns (line, length, first line) of every function longer than LIMIT in one file's text."""
    lines = text.split("\n")
    out, i = [], 0
    while i < len(lines):
        line = lines[i]
        if not START.match(line) or line.startswith(SKIP):
            i += 1
            continue
        k = i   # the signature's last line: the one ending in "{" (a ";" first: a declaration)
        while k < len(lines) and k - i < 8 and not lines[k].rstrip().endswith(("{", ";", "}")):
            k += 1
        if k >= len(lines) or not lines[k].rstrip().endswith("{"):
            i = k + 1
            continue
        depth, j = 0, i
        while j < len(lines):
            depth += lines[j].count("{") - lines[j].count("}")
            if j >= k and depth <= 0:
                break
            j += 1
        length = j - i + 1
        if length > LIMIT and not TABLES.match(line):
            out.append((i + 1, length, line.strip()[:100]))
        i = j + 1
    return out


def check(root):
    root = pathlib.Path(root)
    found = []
    for room in ROOMS:
        for p in sorted((root / room).rglob("*.cpp")):
            for line, length, first in find_long_functions(str(p), p.read_text(errors="replace")):
                found.append(f"{p.relative_to(root)}:{line}: {length} lines (limit {LIMIT}): {first}")
    return found


def self_test():
    body = "\n".join(f"    x += {k};" for k in range(LIMIT))
    long_function = f"int f(int x) {{\n{body}\n    return x;\n}}\n"
    table = f"void addThingCommands(CLI::App& app) {{\n{body}\n}}\n"
    short = "int g(int x) { return x; }\nint h(int x) {\n    return x;\n}\n"
    caught = find_long_functions("a.cpp", short + long_function + table)
    ok = len(caught) == 1 and caught[0][1] == LIMIT + 3
    print("self-test:", "ok" if ok else f"failed: {caught}")
    return 0 if ok else 1


if __name__ == "__main__":
    if len(sys.argv) == 2 and sys.argv[1] == "--self-test":
        sys.exit(self_test())
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    long_functions = check(sys.argv[1])
    for f in long_functions:
        print(f)
    print(f"{len(long_functions)} function(s) over {LIMIT} lines outside binding tables")
    sys.exit(1 if long_functions else 0)
