#!/usr/bin/env python3
"""Time vs number of muscles from bench_model's JSON output (issue 30): a log-log plot and the fitted
exponent of each series (least squares of log time on log N over N >= 8).

    bench_model --benchmark_filter='LockedMvcNMuscles|FreeMovementNMuscles' \
        --benchmark_out=scaling.json --benchmark_out_format=json
    python3 scripts/plot_scaling.py scaling.json docs/scaling_muscles.png
"""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SERIES = {  # benchmark name prefix and its trailing arguments -> label
    ("BM_LockedMvcNMuscles", "1/1000"): "locked MVC 3.5 s, banded Newton, 1000 Hz table",
    ("BM_LockedMvcNMuscles", "1/100"): "locked MVC 3.5 s, banded Newton, 100 Hz table",
    ("BM_LockedMvcNMuscles", "0/1000"): "locked MVC 3.5 s, dense Newton (before)",
    ("BM_FreeMovementNMuscles", "0"): "free movement 1 s, muscle blocks, arrow solve",
    ("BM_FreeMovementNMuscles", "1"): "free movement 1 s, whole System (before)",
}


def read(path):
    with open(path) as f:
        runs = json.load(f)["benchmarks"]
    data = {}
    for r in runs:
        if r.get("run_type", "iteration") != "iteration":
            continue
        name, _, args = r["name"].partition("/")
        n, _, rest = args.partition("/")
        key = (name, rest.split("/real_time")[0])
        if key not in SERIES:
            continue
        scale = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[r["time_unit"]]
        data.setdefault(key, []).append((int(n), r["real_time"] * scale))
    return {k: sorted(v) for k, v in data.items()}


def exponent(points):
    pts = [(math.log(n), math.log(t)) for n, t in points if n >= 8]
    if len(pts) < 2:
        return float("nan")
    mx = sum(x for x, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sum((x - mx) ** 2 for x, _ in pts)


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_scaling.py BENCH.json OUT.png")
    data = read(sys.argv[1])
    if not data:
        sys.exit(f"{sys.argv[1]}: no LockedMvcNMuscles or FreeMovementNMuscles runs: expected bench_model's JSON")
    fig, ax = plt.subplots(figsize=(8, 5))
    for key, points in data.items():
        k = exponent(points)
        ns, ts = zip(*points)
        ax.loglog(ns, ts, "o-", label=f"{SERIES[key]}: N^{k:.2f}")
        print(f"{SERIES[key]}: " + ", ".join(f"N={n} {t * 1e3:.3g} ms" for n, t in points) + f"; exponent (N >= 8) {k:.2f}")
    ax.set_xlabel("muscles N")
    ax.set_ylabel("wall time per trial (s)")
    ax.set_title("Cost vs number of muscles (exponent fitted over N >= 8)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.savefig(sys.argv[2], dpi=110, bbox_inches="tight")


if __name__ == "__main__":
    main()
