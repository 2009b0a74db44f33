#!/usr/bin/env python3
"""Opens a command's index.html in a real browser (headless Chromium) and checks it: no console message
(errors, warnings, logs), every image and video loaded (the page records that in its body's
data-resources attribute), and a screenshot written for a person to look at.

usage: scripts/check_report_in_browser.py --armsim build/armsim --out DIR [--screenshot FILE]
Runs `armsim run --out DIR` first, then checks DIR/index.html; then removes one plot and checks that
the page names it as missing (so the check itself can fail). Exit 0 when all holds, 1 otherwise, 77
(ctest's skip) when Chromium is not installed (Debian's `chromium`, scripts/setup.sh --tests).
"""
import argparse, os, re, shutil, subprocess, sys

BROWSER_ARGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--enable-logging=stderr", "--v=0",
                "--virtual-time-budget=10000", "--hide-scrollbars"]


def open_page(browser, page, extra):
    r = subprocess.run([browser] + BROWSER_ARGS + extra + ["file://" + os.path.abspath(page)],
                       capture_output=True, text=True, timeout=120)
    console = [l for l in r.stderr.splitlines() if ":CONSOLE" in l]
    m = re.search(r'data-resources="([^"]*)"', r.stdout)
    return r.returncode, console, m.group(1) if m else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--armsim", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--screenshot")
    a = ap.parse_args()
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if not browser:
        print("skipped: Chromium is not installed (bash scripts/setup.sh --tests installs Debian's chromium)")
        return 77
    shutil.rmtree(a.out, ignore_errors=True)
    subprocess.run([a.armsim, "run", "--out", a.out, "--quiet"], check=True, stdout=subprocess.DEVNULL)
    page = os.path.join(a.out, "index.html")
    html = open(page, encoding="utf-8").read()
    images, videos = html.count("<img "), html.count("<video ")
    status, console, resources = open_page(browser, page, ["--dump-dom"])
    print(f"{page}: {images} images, {videos} videos; browser exit {status}; console lines {len(console)}; "
          f"resources {resources!r}")
    for line in console:
        print("  console:", line)
    ok = status == 0 and not console and resources == "ok" and images >= 20 and videos >= 2
    if a.screenshot:
        subprocess.run([browser] + BROWSER_ARGS + ["--window-size=1200,2400", "--screenshot=" + os.path.abspath(a.screenshot),
                        "file://" + os.path.abspath(page)], capture_output=True, timeout=120)
        print("screenshot:", a.screenshot, os.path.exists(a.screenshot))
    # The check can fail: a plot removed is named as missing.
    victim = next(os.path.join(d, f) for d, _, fs in os.walk(a.out) for f in sorted(fs) if f.endswith(".png"))
    os.remove(victim)
    _, _, resources = open_page(browser, page, ["--dump-dom"])
    named = resources is not None and os.path.basename(victim) in resources
    print(f"with {os.path.relpath(victim, a.out)} removed: resources {resources!r}")
    return 0 if ok and named else 1


if __name__ == "__main__":
    sys.exit(main())
