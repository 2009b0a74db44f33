#!/usr/bin/env python3
"""Checks that files the docs show whole are shown as they are (no copies drift from the tested file).

In a Markdown file, a line `<!-- verbatim: PATH -->` followed by a fenced code block says the block is
the file PATH (relative to the repository root), byte for byte. Usage:
  check_doc_files.py ROOT          check every docs/*.md and README.md under ROOT (exit 1 on a mismatch)
  check_doc_files.py --self-test   check that an altered block and a missing file are caught
"""
import pathlib
import re
import sys

MARK = re.compile(r"^<!-- verbatim: (\S+) -->\n```[^\n]*\n(.*?)^```$", re.M | re.S)


def find_mismatches(doc_name, text, read_file):
    """read_file(path) -> text or None. Returns one message per block that is not its file."""
    out = []
    for m in MARK.finditer(text):
        path, block = m.group(1), m.group(2)
        line = text.count("\n", 0, m.start()) + 1
        actual = read_file(path)
        if actual is None:
            out.append(f"{doc_name}:{line}: verbatim block of '{path}': no such file")
        elif actual != block:
            out.append(f"{doc_name}:{line}: the block differs from '{path}': copy the file into the block")
    return out


def count_blocks(text):
    return len(MARK.findall(text))


def self_test():
    files = {"a.sh": "echo a\n"}
    good = "x\n<!-- verbatim: a.sh -->\n```bash\necho a\n```\n"
    assert find_mismatches("d", good, files.get) == [], "a faithful block was refused"
    assert count_blocks(good) == 1
    assert find_mismatches("d", good.replace("echo a", "echo b"), files.get), "an altered block passed"
    assert find_mismatches("d", good.replace("a.sh", "b.sh"), files.get), "a missing file passed"
    print("check_doc_files: self-test passed")


def main(argv):
    if argv[1:] == ["--self-test"]:
        self_test()
        return 0
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    root = pathlib.Path(argv[1])

    def read_file(path):
        p = root / path
        return p.read_text() if p.is_file() else None

    docs = sorted((root / "docs").glob("*.md")) + [root / "README.md"]
    problems, blocks = [], 0
    for doc in docs:
        text = doc.read_text()
        blocks += count_blocks(text)
        problems += find_mismatches(str(doc.relative_to(root)), text, read_file)
    for p in problems:
        print(p)
    print(f"check_doc_files: {blocks} verbatim blocks, {len(problems)} mismatches")
    return 1 if problems or blocks == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
