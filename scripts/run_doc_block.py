#!/usr/bin/env python3
"""Runs the shell and Python blocks of a Markdown file as tests (documentation is code).

usage: scripts/run_doc_block.py --list DOC
       scripts/run_doc_block.py DOC LINE --source SRC --build BUILD [--keep]
       scripts/run_doc_block.py --self-test

--list prints one line per runnable block, "LINE LANGUAGE FIRST-COMMAND", where LINE is the line of
its opening fence; blocks fenced as sh, bash or python are runnable, except a block right after a
comment `<!-- doc-test: skip: REASON -->` (the reason is printed on stderr). The second form runs the
block that opens at LINE, as the document shows it, in a fresh temporary folder that holds links to
the source tree's top-level folders (assets, scripts, examples, docs, tests) and to the build folder as
`build`, with `armsim` on PATH, `PYTHONPATH=build/python`, and `ARMSIM_QUICK=1` (population sizes and
fits capped: README, "Trying a command quickly"). A shell block runs under `bash -euo pipefail`, so any
failing line fails it; a Python block runs with `python3`. Exit status: the block's; the folder is
removed unless --keep.
"""
import argparse, os, re, shutil, subprocess, sys, tempfile

RUNNABLE = {"sh": "sh", "bash": "sh", "shell": "sh", "python": "python", "py": "python"}
SKIP = re.compile(r"^<!--\s*doc-test:\s*skip:\s*(.+?)\s*-->\s*$")
LINKED = ["assets", "scripts", "examples", "docs", "tests"]


def find_blocks(text):
    """[(line, language, body, skip reason or None)] of every fenced block with a language."""
    lines = text.split("\n")
    blocks, k = [], 0
    while k < len(lines):
        m = re.match(r"^```(\w+)\s*$", lines[k])
        if not m:
            k += 1
            continue
        start, lang = k, m.group(1)
        end = k + 1
        while end < len(lines) and not lines[end].startswith("```"):
            end += 1
        if end == len(lines):
            raise SystemExit(f"line {start + 1}: block not closed")
        prev = start - 1
        while prev >= 0 and not lines[prev].strip():
            prev -= 1
        skip = SKIP.match(lines[prev]) if prev >= 0 else None
        blocks.append((start + 1, lang, "\n".join(lines[start + 1:end]) + "\n", skip.group(1) if skip else None))
        k = end + 1
    return blocks


def runnable(blocks):
    return [b for b in blocks if b[1] in RUNNABLE and b[3] is None]


def run_block(doc, line, source, build, keep):
    with open(doc, encoding="utf-8") as f:
        blocks = find_blocks(f.read())
    match = [b for b in blocks if b[0] == line]
    if not match or match[0][1] not in RUNNABLE:
        raise SystemExit(f"{doc}:{line}: no sh or python block opens here (blocks open at "
                         f"{', '.join(str(b[0]) for b in runnable(blocks))})")
    _, lang, body, skip = match[0]
    if skip:
        raise SystemExit(f"{doc}:{line}: this block is marked skip: {skip}")
    os.makedirs(os.path.join(build, "doc_tests"), exist_ok=True)
    work = tempfile.mkdtemp(prefix=f"{os.path.basename(doc)}-{line}-", dir=os.path.join(build, "doc_tests"))
    for name in LINKED:
        if os.path.exists(os.path.join(source, name)):
            os.symlink(os.path.join(source, name), os.path.join(work, name))
    os.symlink(os.path.abspath(build), os.path.join(work, "build"))
    os.mkdir(os.path.join(work, ".bin"))
    os.symlink(os.path.join(os.path.abspath(build), "armsim"), os.path.join(work, ".bin", "armsim"))
    # `python3` is the interpreter the tests were configured with (the one with numpy and matplotlib).
    os.symlink(sys.executable, os.path.join(work, ".bin", "python3"))
    env = dict(os.environ)
    env["PATH"] = os.path.join(work, ".bin") + os.pathsep + env.get("PATH", "")
    env["PYTHONPATH"] = os.path.join(os.path.abspath(build), "python") + os.pathsep + env.get("PYTHONPATH", "")
    env["ARMSIM_QUICK"] = "1"
    env.setdefault("MPLBACKEND", "Agg")
    # mpirun as root (the test machines): OpenMPI's own switches, so the README's line runs as written.
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
        env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    env.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
    if RUNNABLE[lang] == "sh":
        cmd = ["bash", "-euo", "pipefail", "-c", body]
    else:
        script = os.path.join(work, ".block.py")
        with open(script, "w", encoding="utf-8") as f:
            f.write(body)
        cmd = [sys.executable, script]
    print(f"{doc}:{line} ({lang}) in {work}:\n{body}", flush=True)
    status = subprocess.call(cmd, cwd=work, env=env)
    if status != 0:
        print(f"{doc}:{line}: the block failed (exit {status}); its folder is kept: {work}", file=sys.stderr)
    elif not keep:
        shutil.rmtree(work, ignore_errors=True)
    return status


def self_test():
    text = ("x\n```sh\necho a\n```\n<!-- doc-test: skip: installs -->\n\n```sh\nexit 1\n```\n"
            "```python\nprint(1)\n```\n```yaml\na: 1\n```\n")
    b = find_blocks(text)
    assert [(x[0], x[1], x[3]) for x in b] == [(2, "sh", None), (7, "sh", "installs"), (10, "python", None),
                                               (13, "yaml", None)], b
    assert [x[0] for x in runnable(b)] == [2, 10]
    assert b[0][2] == "echo a\n"
    try:
        find_blocks("```sh\necho\n")
    except SystemExit as e:
        assert "not closed" in str(e)
    else:
        raise AssertionError("an open block was accepted")
    print("self-test passed")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("doc", nargs="?")
    ap.add_argument("line", nargs="?", type=int)
    ap.add_argument("--list", metavar="DOC")
    ap.add_argument("--source", default=".")
    ap.add_argument("--build", default="build")
    ap.add_argument("--keep", action="store_true")
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()
    if a.self_test:
        return self_test()
    if a.list:
        with open(a.list, encoding="utf-8") as f:
            blocks = find_blocks(f.read())
        for line, lang, body, skip in blocks:
            if lang not in RUNNABLE:
                continue
            if skip:
                print(f"{a.list}:{line}: skipped: {skip}", file=sys.stderr)
                continue
            first = next((l.strip() for l in body.split("\n") if l.strip() and not l.strip().startswith("#")), "")
            print(line, RUNNABLE[lang], first)
        return 0
    if a.doc is None or a.line is None:
        ap.error("give DOC and LINE, --list DOC or --self-test")
    return run_block(a.doc, a.line, os.path.abspath(a.source), a.build, a.keep)


if __name__ == "__main__":
    sys.exit(main())
