#!/usr/bin/env python3
"""The README's out-of-family table (issue 31): every mismatch population (and the default, in family)
as the truth, the default population as the prior, identified from assets/protocols/recommended.yaml
(or --protocol, e.g. two_axis.yaml). The recommended protocol's torques are the thesis's five flexion
MVCs x 3, so the torque-only methods (synergist, synergist-va) on the same data are the five-angle MVC
contrast; "channels" fits every channel. Runs
`armsim validate` per truth (a truth whose summary exists in OUT is reused) and prints one Markdown
row per (truth, method) with bias, RMSE and coverage (+/- one standard error), and writes the rows to
OUT/out_of_family.csv.

usage: scripts/out_of_family_table.py [--armsim build/armsim] [--subjects 100] [--protocol FILE] [--out out/out_of_family]
"""
import argparse, csv, glob, os, subprocess, sys

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--armsim", default="build/armsim")
    ap.add_argument("--subjects", type=int, default=100)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--protocol", default="assets/protocols/recommended.yaml")
    ap.add_argument("--out", default="out/out_of_family")
    a = ap.parse_args()
    protocol = os.path.splitext(os.path.basename(a.protocol))[0]
    truths = ["assets/subjects/default_population.yaml"] + sorted(glob.glob("assets/subjects/mismatch/*.yaml"))
    rows = []
    for truth in truths:
        name = os.path.splitext(os.path.basename(truth))[0].replace("default_population", "in family")
        out = os.path.join(a.out, name.replace(" ", "_"))
        summary = os.path.join(out, "elbow_validation_summary.csv")
        if not os.path.exists(summary):
            cmd = [a.armsim, "validate", "--truth", "elbow", "--truth-population", truth, "--prior",
                   "assets/subjects/default_population.yaml", "--protocol", a.protocol,
                   "--subjects", str(a.subjects), "--jobs", str(a.jobs), "--out", out]
            print(" ".join(cmd), file=sys.stderr, flush=True)
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        for r in csv.DictReader(open(summary)):
            if r["method"] == "thesis":
                continue
            label = "every channel" if r["method"] == "channels" else "torque only"
            if protocol != "recommended":
                label += " (" + protocol + ")"
            rows.append(dict(r, truth=name, protocol=label))
    keys = ["truth", "protocol", "method", "subjects", "converged", "mass_bias_pct", "mass_bias_se_pct", "mass_rmse_pct",
            "mass_rmse_se_pct", "mass_coverage", "mass_coverage_se", "tendon_bias_mm", "tendon_rmse_mm",
            "tendon_rmse_se_mm", "tendon_coverage", "max_force_bias_pct", "max_force_rmse_pct", "max_force_coverage"]
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "out_of_family.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    f = lambda r, k, d=1: ("%." + str(d) + "f") % float(r[k]) if r.get(k) not in (None, "") else "-"
    print("| truth | data | method | mass bias % | mass RMSE % | mass coverage | L0T bias mm | L0T RMSE mm | L0T coverage | F0 RMSE % | F0 coverage |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %s | %s | %s +/- %s | %s +/- %s | %s +/- %s | %s | %s +/- %s | %s | %s | %s |" % (
            r["truth"], r["protocol"], r["method"], f(r, "mass_bias_pct"), f(r, "mass_bias_se_pct"),
            f(r, "mass_rmse_pct"), f(r, "mass_rmse_se_pct"), f(r, "mass_coverage", 2), f(r, "mass_coverage_se", 2),
            f(r, "tendon_bias_mm"), f(r, "tendon_rmse_mm"), f(r, "tendon_rmse_se_mm"), f(r, "tendon_coverage", 2),
            f(r, "max_force_rmse_pct"), f(r, "max_force_coverage", 2)))

if __name__ == "__main__":
    main()
