#!/usr/bin/env bash
# Installs what RROSFuzz needs, idempotently: Debian packages that are missing,
# a virtual environment in .venv, and the project (with its native build) in it.
#   scripts/setup.sh            core + test dependencies
# Environment: PYTHON (default: python3.11, else python3; must be 3.11),
#              VENV (default: .venv), RROSFUZZ_EXTRAS (default: test,adapters,engines).
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(
  cmake g++ make                      # native build
  libeigen3-dev liborocos-kdl-dev     # Eigen, Orocos KDL
  liburdfdom-dev libconsole-bridge-dev libexpat1-dev  # URDF parsing (urdfdom), XML guard
  ros-sensor-msgs ros-geometry-msgs   # real ROS .msg definitions (--msg-path, tests)
  chromium                            # renders the HTML report headless (tests)
  python3-pykdl                       # PyKDL, a third-party target (adapters/)
)

scripts/apt-ensure.sh "${APT_PACKAGES[@]}"

VENV=${VENV:-.venv}
PYTHON=${PYTHON:-$(command -v python3.11 || command -v python3)}
if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
  echo "setup: $PYTHON is $("$PYTHON" --version 2>&1); RROSFuzz needs Python 3.11 (atheris 3.0.0 wheels)" >&2
  exit 1
fi
if [ ! -x "$VENV/bin/python" ]; then
  echo "setup: creating $VENV"
  "$PYTHON" -m venv "$VENV"
fi
echo "setup: installing the project into $VENV (native build in build/)"
# constraints.txt: the tested versions of every package (pyproject.toml has the supported ranges)
# pip's own status, not grep's (grep -v finds nothing to print when all is well): an interrupted
# or failed install went on to the import check, which then blamed the native module
# (pipefail: the pipeline's status is pip's)
if "$VENV/bin/python" -m pip install -q --disable-pip-version-check -c constraints.txt \
  -e ".[${RROSFUZZ_EXTRAS:-test,adapters,engines}]" 2>&1 \
  | { grep -v "is ignored: it is neither a file nor a directory" || true; }; then
  status=0
else
  status=$?
fi
if [ "$status" -ne 0 ]; then
  echo "setup: pip install into $VENV failed or was interrupted (status $status): its output is above; run the same command again" >&2
  exit "$status"
fi
"$VENV/bin/python" -c "import native, python_impl" \
  || { echo "setup: the install did not produce an importable native module" >&2; exit 1; }
