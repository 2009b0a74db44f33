"""Example 1: the biceps's steady force-length curve and the elbow muscles' moment arms.

    PYTHONPATH=build/python python3 examples/force_length_and_moment_arms.py --out out/examples

Writes force_length.png, moment_arms.png and the numbers as CSV.
"""
import argparse
import os

import matplotlib
import numpy as np

matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))
import matplotlib.pyplot as plt  # noqa: E402

import armsim  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/examples", help="output folder")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    thesis = armsim.Model.load("thesis")
    p = thesis.parameters()
    paths = np.linspace(0.27, p["max_path_length"], 60)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    rows = []
    for u in (1.0, 0.5, 0.2):
        force = [armsim.steady_state(thesis, float(x), u)["force_N"] for x in paths]
        rows.append(force)
        ax.plot(100 * paths, force, label=f"U = {u:g}")
    ax.set(xlabel="path length P (cm)", ylabel="steady force Fse (N)",
           title=f"{p['name']}: steady isometric force (M = {1000 * p['mass']:.0f} g)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1))
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "force_length.png"), dpi=120, bbox_inches="tight")
    np.savetxt(os.path.join(args.out, "force_length.csv"), np.column_stack([paths, *rows]), delimiter=",",
               header="path_length_m,force_U1_N,force_U05_N,force_U02_N", comments="")

    elbow = armsim.Model.load("elbow")
    angles = np.arange(10.0, 141.0, 5.0)
    g = elbow.geometry(list(angles))
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, name in enumerate(elbow.muscles):   # heads on one path share a curve: dashes tell them apart
        ax.plot(angles, 100 * g["moment_arm_m"][:, i], label=name, linestyle=["-", "--", ":"][i % 3])
    ax.axhline(0, color="grey", lw=0.8)
    ax.set(xlabel="elbow flexion (deg)", ylabel="moment arm (cm), + flexes", title="Elbow model: moment arms")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1), fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "moment_arms.png"), dpi=120, bbox_inches="tight")
    np.savetxt(os.path.join(args.out, "moment_arms.csv"), np.column_stack([angles, g["moment_arm_m"]]), delimiter=",",
               header="flexion_deg," + ",".join(f"{m}_m" for m in elbow.muscles), comments="")
    peak = paths[int(np.argmax(rows[0]))]
    print(f"force-length peak {max(rows[0]):.1f} N at P = {100 * peak:.1f} cm; wrote {args.out}/force_length.png, "
          f"moment_arms.png and their CSVs")


if __name__ == "__main__":
    main()
