#!/usr/bin/env bash
# Prepare this checkout to run: Debian packages for headless MuJoCo rendering, a
# virtual environment in .venv with the project installed (editable, with test extras).
#
# Idempotent and silent when nothing needs doing:
#   * a Debian package is installed only when `dpkg -s` says it is missing
#     (`apt-get update` runs once, first); without root and without passwordless
#     sudo, the missing packages and the command to install them are printed and
#     the script carries on (the simulation and the tests that do not render work);
#   * .venv is created only when missing; pip is upgraded and the project installed
#     only when pyproject.toml changed since the last install (its SHA-256 is kept in
#     .venv/.twin-bootstrap-stamp) or `twin` cannot be imported.
#   * the dependencies are pinned to the known-good set in constraints.txt (CI's);
#     TWIN_NO_CONSTRAINTS=1 installs the newest versions pyproject.toml allows instead.
# Environment: PYTHON (default python3) picks the interpreter for a new .venv;
# TWIN_SKIP_APT=1 skips the Debian packages.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
STAMP="$VENV/.twin-bootstrap-stamp"
PYTHON="${PYTHON:-python3}"

say() { echo "bootstrap: $*" >&2; }

# MUJOCO_GL=egl renders on the CPU through Mesa's llvmpipe: libEGL (glvnd) with Mesa's
# EGL vendor library and DRI drivers, plus libOpenGL/libGL for PyOpenGL.
# MUJOCO_GL=osmesa needs libosmesa6.
APT_PACKAGES=(libegl1 libegl-mesa0 libgl1-mesa-dri libgl1 libopengl0 libosmesa6)

if ! command -v "$PYTHON" >/dev/null 2>&1; then
    say "error: $PYTHON not found; install Python 3.10 or newer (Debian: apt-get install python3)"
    exit 1
fi
if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 10))'; then
    say "error: $("$PYTHON" --version 2>&1) is too old; twin needs Python 3.10 or newer"
    exit 1
fi

# ---- Debian packages --------------------------------------------------------
install_debian_packages() {
    [[ "${TWIN_SKIP_APT:-0}" == 1 ]] && return 0
    command -v dpkg >/dev/null 2>&1 || return 0     # not Debian: nothing to check
    local wanted=("${APT_PACKAGES[@]}") missing=() p
    # Debian's python3 has no ensurepip (so no `python -m venv`) without python3-venv.
    if [[ ! -x "$VENV/bin/python" ]] && ! "$PYTHON" -c 'import ensurepip' >/dev/null 2>&1; then
        wanted+=("python3-venv")
    fi
    for p in "${wanted[@]}"; do
        dpkg -s "$p" 2>/dev/null | grep -q '^Status: install ok installed' || missing+=("$p")
    done
    [[ ${#missing[@]} -eq 0 ]] && return 0

    local sudo=()
    if [[ "$(id -u)" -ne 0 ]]; then
        if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
            sudo=(sudo -n)
        else
            say "missing Debian packages: ${missing[*]}"
            say "install them as root:  apt-get update && apt-get install -y ${missing[*]}"
            say "continuing without them (headless rendering may not work)"
            return 0
        fi
    fi
    say "installing Debian packages: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    "${sudo[@]}" apt-get update -qq
    local available=()
    for p in "${missing[@]}"; do
        if apt-cache show "$p" >/dev/null 2>&1; then
            available+=("$p")
        else
            say "warning: no Debian package $p in this release; skipped"
        fi
    done
    if [[ ${#available[@]} -gt 0 ]]; then
        "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${available[@]}" >/dev/null
    fi
}
install_debian_packages

# ---- virtual environment and the project --------------------------------------
if [[ ! -x "$VENV/bin/python" ]]; then
    say "creating $VENV"
    "$PYTHON" -m venv "$VENV"
    rm -f "$STAMP"
fi

hash="$(cat "$ROOT/pyproject.toml" "$ROOT/constraints.txt" | sha256sum | cut -d' ' -f1)"
constraints=(-c "$ROOT/constraints.txt")
[[ "${TWIN_NO_CONSTRAINTS:-0}" == 1 ]] && constraints=()
if [[ ! -f "$STAMP" ]] || [[ "$(cat "$STAMP")" != "$hash" ]] \
        || ! "$VENV/bin/python" -c 'import twin' >/dev/null 2>&1; then
    say "installing the project into $VENV (pyproject.toml or constraints.txt changed, or not installed yet)"
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --upgrade pip
    (cd "$ROOT" && "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "${constraints[@]}" -e '.[test]')
    echo "$hash" > "$STAMP"
fi
