#!/usr/bin/env bash
# Installs the Debian packages the project builds and tests with, only those missing.
# Idempotent: a machine that has everything gets no apt call at all.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libfcl-dev liburdfdom-dev libtinyxml-dev libhdf5-dev libcli11-dev
  nlohmann-json3-dev
  # Obstacles given as meshes and point clouds (Assimp) and as OctoMap octrees (issue 26);
  # convex hulls of robot link meshes (Qhull, issue 28).
  libassimp-dev liboctomap-dev libqhull-dev
  # The k-d tree over the bundle's edge end poses, pose goals' coverage (issue 29).
  libnanoflann-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-jsonschema
  # The Python module (python/) and its tests: built for and run by Debian's /usr/bin/python3.
  pybind11-dev python3-dev python3-numpy python3-pytest
  # Optional for the build (lazyboe-bench skips what is missing, and says so), installed so
  # that the demo and the tests cover OMPL's planners and the benchmark figures.
  libompl-dev python3-matplotlib
  # lazyboe-view (issue 17): three.js (with OrbitControls) inlined into its pages, and the
  # browser its tests open them in (headless; they are skipped without it).
  libjs-three chromium
  # Optional for the build (lazyboe-build/-perturb run across MPI ranks with it; without it
  # they say so when asked for MPI), installed so that the MPI tests run (issue 18).
  libopenmpi-dev openmpi-bin
)
# Extra packages a caller asks for.
packages+=("$@")

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done

if [[ ${#missing[@]} -eq 0 ]]; then
  exit 0
fi

echo "install-deps: installing ${missing[*]}" >&2
sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "install-deps: not root and no sudo; install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
