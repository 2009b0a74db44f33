#!/usr/bin/env python3
"""Mends a muscle path of a model file against the moment-arm targets (issue 28, "paths mended where
they are wrong"): moves a few named coordinates of the path (a via point, the origin or insertion, a
wrap radius) so the muscle's moment arm about the elbow falls inside the published bands of the target
file, each coordinate held near its source value by a Gaussian prior (sd given per coordinate).

The score is what `armsim model check` judges: for every moment-arm target of the muscle,
((distance outside the band) / tolerance)^2 plus 0.05 ((value - band middle) / tolerance)^2, which keeps
the curve off the edges; plus sum ((x - x0) / sd)^2 over the coordinates. The search is a pattern search
(each coordinate by +/- step, steps halved when nothing improves), so no optimiser library is needed.
It prints the coordinates before and after, and each target's value, band and verdict; it never writes
the model file: copy the printed lines into it (with a comment naming this script).

usage: scripts/mend_paths.py --muscle BRD --free origin.location.0:0.004 --free origin.location.1:0.01
           [--model assets/models/twin.yaml] [--targets FILE] [--armsim build/armsim]
Candidates the model refuses (a point inside a wrap surface) are skipped.
A coordinate is a dotted path inside the muscle's `path:` section (`via.1.cylinder.radius`,
`insertion.location.1`), then `:sd` in metres.
"""
import argparse, copy, csv, os, subprocess, sys, tempfile
import yaml

def get(node, keys):
    for k in keys:
        node = node[int(k)] if isinstance(node, list) else node[k]
    return node

def put(node, keys, value):
    parent = get(node, keys[:-1])
    if isinstance(parent, list):
        parent[int(keys[-1])] = value
    else:
        parent[keys[-1]] = value

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--muscle", required=True)
    ap.add_argument("--free", action="append", required=True, help="path.coordinate:sd (m)")
    ap.add_argument("--model", default="assets/models/twin.yaml")
    ap.add_argument("--targets", default="assets/reference/elbow_targets.yaml")
    ap.add_argument("--armsim", default="build/armsim")
    ap.add_argument("--min-step", type=float, default=2e-4, help="m; the search stops below it")
    a = ap.parse_args()

    model = yaml.safe_load(open(a.model))
    here = os.path.dirname(os.path.abspath(a.model))
    for m in model["muscles"]:  # the temporary copy lives elsewhere: make relative files absolute
        if "fibre_types" in m and not os.path.isabs(m["fibre_types"]):
            m["fibre_types"] = os.path.normpath(os.path.join(here, m["fibre_types"]))
    muscle = next((m for m in model["muscles"] if m["name"] == a.muscle), None)
    if muscle is None:
        sys.exit("mend_paths: no muscle '%s' in %s" % (a.muscle, a.model))
    free = []
    for f in a.free:
        name, _, sd = f.rpartition(":")
        keys = name.split(".")
        try:
            x0 = float(get(muscle["path"], keys))
            sd = float(sd)
        except (KeyError, IndexError, ValueError, TypeError):
            sys.exit("mend_paths: --free '%s': expected path.coordinate:sd with a number at the path of %s" % (f, a.muscle))
        free.append((name, keys, x0, sd))

    tmp = tempfile.mkdtemp(prefix="mend_paths_")
    evaluations = [0]

    def score(x):
        trial = copy.deepcopy(model)
        path = next(m for m in trial["muscles"] if m["name"] == a.muscle)["path"]
        for (_, keys, _, _), v in zip(free, x):
            put(path, keys, float(v))
        f = os.path.join(tmp, "model.yaml")
        yaml.safe_dump(trial, open(f, "w"), sort_keys=False)
        out = os.path.join(tmp, "check")
        run = subprocess.run([a.armsim, "model", "check", "--model", f, "--targets", a.targets, "--out", out],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        evaluations[0] += 1
        if run.returncode != 0:  # e.g. a point moved inside a wrap surface: not a candidate
            return float("inf"), run.stderr.strip()
        rows = [r for r in csv.DictReader(open(os.path.join(out, "scorecard.csv")))
                if r["kind"] == "moment_arm" and r["muscle"] == a.muscle]
        s = 0.0
        for r in rows:
            v, lo, hi, tol = (float(r[k]) for k in ("value", "lower", "upper", "tolerance"))
            outside = max(lo - v, v - hi, 0.0)
            s += (outside / tol) ** 2 + 0.05 * ((v - 0.5 * (lo + hi)) / tol) ** 2
        s += sum(((v - x0) / sd) ** 2 for (_, _, x0, sd), v in zip(free, x))
        return s, rows

    x = [x0 for _, _, x0, _ in free]
    best, rows0 = score(x)
    if best == float("inf"):
        sys.exit("mend_paths: the model as given fails: " + rows0)
    step = [sd for _, _, _, sd in free]
    while max(step) > a.min_step:
        improved = False
        for i in range(len(x)):
            for sign in (1, -1):
                y = list(x)
                y[i] += sign * step[i]
                s, _ = score(y)
                if s < best - 1e-9:
                    best, x, improved = s, y, True
                    break
        if not improved:
            step = [0.5 * h for h in step]
    _, rows = score(x)
    print("%s: %d evaluations, score %.3f" % (a.muscle, evaluations[0], best))
    for (name, _, x0, sd), v in zip(free, x):
        print("  %-28s %.5f -> %.5f  (moved %+.1f mm, prior sd %.1f mm)" % (name, x0, v, 1e3 * (v - x0), 1e3 * sd))
    print("  %8s %9s %9s %15s %s" % ("flexion", "before", "after", "band", ""))
    for r0, r in zip(rows0, rows):
        ok = "pass" if r["pass"] == "1" else "FAIL"
        print("  %8s %9.1f %9.1f  [%5.1f, %5.1f] +/-%.0f %s" % (r["flexion_deg"], 1e3 * float(r0["value"]),
              1e3 * float(r["value"]), 1e3 * float(r["lower"]), 1e3 * float(r["upper"]),
              1e3 * float(r["tolerance"]), ok))

if __name__ == "__main__":
    main()
