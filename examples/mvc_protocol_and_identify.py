"""Example 2: simulate the thesis's MVC protocol, then identify biceps mass and tendon length from it.

    PYTHONPATH=build/python python3 examples/mvc_protocol_and_identify.py --out out/examples

Runs assets/protocols/mvc_force_angle.yaml (five elbow angles x three repetitions, 3 s efforts,
tared transducer, synthetic EMG) on the thesis subject, takes the forces the experimenter reports
(tared torque / moment arm), identifies mass M and optimal tendon length L0T with the steady model and
with the corrected (faithful) model, and compares both with the subject's truth. Writes
mvc_identification.png (data, fits, convergence) and mvc_identification.csv.
"""
import argparse
import csv
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

    subject = armsim.Model.load("thesis")  # the protocol's subject
    truth = subject.parameters()
    run = armsim.run_protocol("protocols/mvc_force_angle.yaml")
    trials = run["trials"]
    data = {"angle_deg": trials["elbow_angle_deg"], "force_N": trials["force_measured_N"],
            "trial": trials["repetition"]}
    start = {"mass": 0.330, "optimal_tendon_length": 0.22}  # the thesis's start (Tables 7.2, 7.3)
    reports = {forward: armsim.identify(subject, data, forward=forward, start=start)
               for forward in ("steady", "corrected")}

    rows = []
    print(f"truth: M = {1000 * truth['mass']:.2f} g, L0T = {100 * truth['optimal_tendon_length']:.3f} cm")
    for forward, r in reports.items():
        m, l0t = r["estimate"]["mass"], r["estimate"]["optimal_tendon_length"]
        ci = [p["interval"] for p in r["parameters"]]
        print(f"{forward:9s}: M = {1000 * m:.2f} g [{1000 * ci[0][0]:.2f}, {1000 * ci[0][1]:.2f}] "
              f"({100 * (m / truth['mass'] - 1):+.2f} %), L0T = {100 * l0t:.3f} cm "
              f"[{100 * ci[1][0]:.3f}, {100 * ci[1][1]:.3f}] ({1000 * (l0t - truth['optimal_tendon_length']):+.2f} mm), "
              f"{r['stop_reason']}, correlation {r['uncertainty']['correlation'][0, 1]:+.2f}")
        rows.append([forward, m, ci[0][0], ci[0][1], l0t, ci[1][0], ci[1][1], r["rms_residual_N"], r["stop_reason"]])
    with open(os.path.join(args.out, "mvc_identification.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["forward", "mass_kg", "mass_lower_kg", "mass_upper_kg", "tendon_length_m", "tendon_lower_m",
                    "tendon_upper_m", "rms_residual_N", "stop_reason"])
        w.writerows(rows)

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.3))
    left.plot(trials["elbow_angle_deg"], trials["force_measured_N"], "ko", label="protocol: tared torque / moment arm")
    for forward, r in reports.items():
        obs = r["observations"]
        order = np.argsort(obs["angle_rad"])
        left.plot(np.degrees(obs["angle_rad"][order]), obs["model_N"][order], "-", label=f"{forward} model at estimate")
        h = r["history"]
        right.semilogy(h["iteration"], np.maximum(np.sqrt(2 * h["cost_N2"]), 1e-12), "o-", label=forward)
    left.set(xlabel="included elbow angle (deg, 180 = extended)", ylabel="biceps force (N)",
             title="MVC protocol, five angles x three")
    left.legend(loc="upper center", bbox_to_anchor=(0.5, -0.15), fontsize=8)  # below: the right panel is beside it
    right.set(xlabel="iteration (corrected: faithful corrections)", ylabel="residual norm (N)",
              title="convergence")
    right.legend(loc="upper left", bbox_to_anchor=(1.01, 1))
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "mvc_identification.png"), dpi=120, bbox_inches="tight")
    print(f"wrote {args.out}/mvc_identification.png, mvc_identification.csv")


if __name__ == "__main__":
    main()
