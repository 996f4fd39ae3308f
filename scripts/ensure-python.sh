#!/usr/bin/env bash
# Makes the Python environment of the bindings' tests, only what is missing (idempotent): a
# virtualenv at $VENV (default .venv, from `python3`) with maturin, pytest, ray, gymnasium and pettingzoo from PyPI.
# Fails with one clear line when something cannot be had.
set -euo pipefail

VENV=${VENV:-.venv}
say() { echo "python: $*" >&2; }
die() { echo "python: error: $*" >&2; exit 1; }

PY=${PYTHON:-python3}
command -v "$PY" >/dev/null 2>&1 || die "$PY not found: install Python 3.9 or newer (Debian: apt-get install python3 python3-venv)"
"$PY" -c 'import sys; sys.exit(sys.version_info < (3, 9))' || die "$PY is older than 3.9"

if ! "$VENV/bin/python" -c pass >/dev/null 2>&1; then
    if [ -e "$VENV" ] && [ ! -f "$VENV/pyvenv.cfg" ]; then
        die "$VENV exists and is not a virtualenv: remove it or set VENV"
    fi
    rm -rf "$VENV"  # missing, or made by an interpreter that is gone
    say "creating virtualenv $VENV from $(command -v "$PY")"
    if ! "$PY" -m venv "$VENV" >/dev/null 2>&1; then
        rm -rf "$VENV"
        # Debian's python3 needs python3-venv (ensurepip) for this.
        if command -v apt-get >/dev/null 2>&1; then
            SUDO=""
            [ "$(id -u)" -eq 0 ] || SUDO="sudo -n"
            say "installing python3-venv (apt-get)"
            export DEBIAN_FRONTEND=noninteractive
            { $SUDO apt-get update -qq && $SUDO apt-get install -y -qq python3-venv; } >/dev/null 2>&1 \
                || die "cannot create a virtualenv with $PY -m venv, nor install python3-venv"
        fi
        "$PY" -m venv "$VENV" >/dev/null 2>&1 || { rm -rf "$VENV"; die "cannot create a virtualenv with $PY -m venv (Debian: apt-get install python3-venv)"; }
    fi
fi

# What the tests need, installed only when it cannot be imported.
need=()
"$VENV/bin/python" -c 'import maturin' 2>/dev/null || need+=("maturin>=1.9.4,<2")
"$VENV/bin/python" -c 'import pytest' 2>/dev/null || need+=("pytest>=7")
"$VENV/bin/python" -c 'import ray' 2>/dev/null || need+=("ray>=2.9")
"$VENV/bin/python" -c 'import gymnasium' 2>/dev/null || need+=("gymnasium>=1.0")
"$VENV/bin/python" -c 'import pettingzoo' 2>/dev/null || need+=("pettingzoo>=1.24")
if [ ${#need[@]} -gt 0 ]; then
    say "installing ${need[*]} into $VENV (pip)"
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "${need[@]}" \
        || die "pip install ${need[*]} failed (no network to PyPI?)"
fi
exit 0
