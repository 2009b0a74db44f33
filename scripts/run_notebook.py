#!/usr/bin/env python3
"""Executes a notebook of examples/notebooks/ for ctest: it must be stored without outputs (cells
unexecuted), then every cell must run without an error in a fresh Python 3 kernel (nbclient, Debian's
python3-nbclient and python3-ipykernel). Runs in a temporary folder; the kernel inherits the
environment (PYTHONPATH to the build's package, ARMSIM_QUICK=1). Exit 0: ran; 1: a stored output or a
failing cell (named); 77: nbclient or ipykernel missing (ctest: skipped)."""
import os
import sys
import tempfile

try:
    import nbclient
    import nbformat
    import ipykernel  # noqa: F401  (the kernel nbclient starts)
except ImportError as e:
    print(f"skipped: {e} (install python3-nbclient python3-ipykernel: scripts/setup.sh --tests)")
    sys.exit(77)


def main():
    path = os.path.abspath(sys.argv[1])
    nb = nbformat.read(path, as_version=4)
    stored = [i for i, c in enumerate(nb.cells)
              if c.cell_type == "code" and (c.get("outputs") or c.get("execution_count") is not None)]
    if stored:
        print(f"{path}: cells {stored} are stored with outputs: clear them "
              f"(jupyter nbconvert --clear-output --inplace {os.path.basename(path)})")
        return 1
    os.environ.setdefault("PYDEVD_DISABLE_FILE_VALIDATION", "1")   # the kernel's debugger notice
    with tempfile.TemporaryDirectory(prefix="armsim-notebook-") as work:
        client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": work}})
        try:
            client.execute()
        except nbclient.exceptions.CellExecutionError as e:
            print(f"{path}: a cell failed:\n{e}")
            return 1
    images = sum(1 for c in nb.cells if c.cell_type == "code" for o in c.outputs if "image/png" in o.get("data", {}))
    print(f"{os.path.basename(path)}: {len(nb.cells)} cells ran, {images} figures")
    return 0


if __name__ == "__main__":
    sys.exit(main())
