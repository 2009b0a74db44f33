#!/usr/bin/env bash
# Installs the Debian 12 packages armsim builds and runs with; `--tests` also those only the tests
# need (clang for scripts/sanitize.sh and scripts/fuzz.sh; Slurm and munge for the local cluster of
# scripts/slurm-local.sh; Chromium opens the reports, scripts/check_report_in_browser.py). Idempotent: packages already present are skipped; a held dpkg lock is waited
# for instead of failing; sudo is used when not root.
set -euo pipefail

with_tests=0
for arg in "$@"; do
  case "$arg" in
    --tests) with_tests=1 ;;
    *) echo "setup: unknown option '$arg': expected --tests or nothing" >&2; exit 2 ;;
  esac
done

packages=(
  build-essential cmake pkg-config
  libsimbody-dev libeigen3-dev libceres-dev libopencv-dev libosmesa6-dev
  libgtest-dev libgmock-dev libbenchmark-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libplplot-dev plplot-driver-cairo libfftw3-dev libfmt-dev libtinyxml2-dev
  libavcodec-dev libavformat-dev libswscale-dev libpng-dev
  libopenmpi-dev openmpi-bin
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib
)
test_packages=(
  clang libclang-rt-14-dev
  slurm-wlm munge
  chromium
  python3-nbclient python3-ipykernel jupyter-nbconvert   # the notebooks, executed by ctest
  python3-pandas                                         # optional for users; its tests run when present
)
[ $with_tests -eq 1 ] && packages+=("${test_packages[@]}")

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: not root and no sudo; install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo env DEBIAN_FRONTEND=noninteractive)
fi

# Another apt/dpkg process (unattended upgrades, a second shell) may hold the locks: wait for it
# (up to 10 minutes) instead of failing. DPkg::Lock::Timeout covers the dpkg lock itself.
wait_for_package_manager() {
  for _ in $(seq 1 120); do
    if ! pgrep -x 'apt-get|apt|dpkg|unattended-upgr' >/dev/null 2>&1; then return 0; fi
    echo "setup: another package manager is running; waiting for it to finish..."
    sleep 5
  done
}
apt_opts=(-o DPkg::Lock::Timeout=600 -y -q)
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
wait_for_package_manager
"${sudo_cmd[@]}" apt-get "${apt_opts[@]}" update
wait_for_package_manager
"${sudo_cmd[@]}" apt-get "${apt_opts[@]}" install --no-install-recommends "${missing[@]}"
