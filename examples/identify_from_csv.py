"""Identify muscle parameters from a CSV of measured data and plot the fit.

    PYTHONPATH=build/python python3 examples/identify_from_csv.py [DATA.csv] --out out/examples

Force data (columns force_N and one of path_m, path_cm, angle_deg; optional activation, trial) are
identified as `armsim identify` does: the biceps's mass and optimal tendon length by Levenberg-Marquardt
with the steady model, re-checked by the faithful model. Torque data (flexion_deg, torque_Nm; optional
effort, level, repetition) go to every elbow method as `armsim identify-torque` does. Default data: the
thesis's two measured forces (assets/measured/thesis_measured.csv). Writes identify_fit.png and
identify_estimates.csv.
"""
import argparse
import csv
import os

import matplotlib
import numpy as np

matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))
import matplotlib.pyplot as plt  # noqa: E402

import armsim  # noqa: E402


def read_header(path):
    """The first line that is neither empty nor a comment: the CSV's column names."""
    here = path if os.path.exists(path) else os.path.join(os.path.dirname(__file__), "..", "assets", path)
    with open(here) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                return [c.strip() for c in line.split(",")]
    raise ValueError(f"{path}: no header line")


def identify_forces(path, model_name, out):
    model = armsim.Model.load(model_name)
    r = armsim.identify(model, path, start={"mass": 0.330, "optimal_tendon_length": 0.22})
    m, l0t = r["estimate"]["mass"], r["estimate"]["optimal_tendon_length"]
    print(f"{path}: M = {1000 * m:.2f} g, L0T = {100 * l0t:.3f} cm ({r['stop_reason']}, {r['iterations']} iterations, "
          f"rms {r['rms_residual_N']:.3g} N; faithful re-check rms {r['model_checks'][1]['rms_residual_N']:.3g} N)")
    fitted = model.with_muscle(mass=m, optimal_tendon_length=l0t)
    obs = r["observations"]
    paths = np.linspace(0.8 * obs["path_m"].min(), min(1.05 * obs["path_m"].max(), fitted.parameters()["max_path_length"]), 80)
    curve = [armsim.steady_state(fitted, float(p), 1.0)["force_N"] for p in paths]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.3))
    left.plot(100 * obs["path_m"], obs["measured_N"], "ko", label="measured")
    left.plot(100 * paths, curve, "-", label=f"steady model, M {1000 * m:.1f} g, L0T {100 * l0t:.2f} cm")
    left.set(xlabel="path length (cm)", ylabel="force (N)", title="data and the identified muscle at U = 1")
    left.legend(loc="upper center", bbox_to_anchor=(0.5, -0.15), fontsize=8)  # below: the right panel is beside it
    h = r["history"]
    right.semilogy(h["iteration"], np.maximum(np.sqrt(2 * h["cost_N2"]), 1e-12), "o-")
    right.set(xlabel="iteration", ylabel="residual norm (N)", title=f"{r['method']}: {r['stop_reason']}")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "identify_fit.png"), dpi=120, bbox_inches="tight")
    return [["lm", m, *r["parameters"][0]["interval"], l0t, *r["parameters"][1]["interval"], r["rms_residual_N"]]]


def identify_torque(path, out):
    estimates = armsim.identify_torque(path)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    rows = []
    for e in estimates:
        print(f"{e['method']:13s} M = {1000 * e['mass_kg']:.1f} g [{1000 * e['mass_interval_kg'][0]:.1f}, "
              f"{1000 * e['mass_interval_kg'][1]:.1f}], L0T = {100 * e['tendon_length_m']:.2f} cm, "
              f"residuals p = {e['residual_check']['p_value']:.3f}")
        rows.append([e["method"], e["mass_kg"], *e["mass_interval_kg"], e["tendon_length_m"], *e["tendon_interval_m"],
                     e.get("rms_residual_Nm", e.get("rms_residual_N"))])
    table = armsim.read_torque_data(path)
    ax.plot(table["flexion_deg"], table["torque_Nm"], "ko", label="measured")
    for e in estimates:
        k = np.isfinite(e["predicted_torque_Nm"])
        ax.plot(table["flexion_deg"][k], e["predicted_torque_Nm"][k], "x", label=e["method"])
    ax.set(xlabel="elbow flexion (deg, 0 = extended)", ylabel="tared torque (N m)", title="torque data and fits")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1))
    fig.tight_layout()
    fig.savefig(os.path.join(out, "identify_fit.png"), dpi=120, bbox_inches="tight")
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="measured/thesis_measured.csv",
                        help="CSV path (or a name under assets/)")
    parser.add_argument("--model", default="thesis", help="model for force data (name or file)")
    parser.add_argument("--out", default="out/examples", help="output folder")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    columns = read_header(args.data)
    rows = identify_torque(args.data, args.out) if "torque_Nm" in columns else identify_forces(args.data, args.model,
                                                                                               args.out)
    with open(os.path.join(args.out, "identify_estimates.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["method", "mass_kg", "mass_lower_kg", "mass_upper_kg", "tendon_length_m", "tendon_lower_m",
                    "tendon_upper_m", "rms_residual"])
        w.writerows(rows)
    print(f"wrote {args.out}/identify_fit.png, identify_estimates.csv")


if __name__ == "__main__":
    main()
