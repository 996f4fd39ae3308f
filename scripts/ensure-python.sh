#!/usr/bin/env bash
# Makes the project's Python environment, only what is missing (idempotent): a virtualenv at
# $VENV (default .venv, from `python3`) with, from PyPI,
#   tools  maturin, pytest, ray, gymnasium and pettingzoo (the bindings' tests), and
#   sumo   SUMO's own wheel eclipse-sumo, version $SUMO_PIP_VERSION (default 1.28.0): headers,
#          libsumocpp and programs (`make ... SUMO=pip` builds against it).
#   wheel  maturin alone (`make wheel` builds the release wheel with it).
#   libsumo  SUMO's Python libsumo wheel, version $LIBSUMO_VERSION (the SUMO bkpbs is built
#          against): a TraCI loop in the virtualenv then runs SUMO in-process (`make wheel`).
# The arguments name which (default: tools). Fails with one clear line when something cannot be had.
set -euo pipefail

want_tools=0
want_sumo=0
want_maturin=0
want_libsumo=0
[ $# -gt 0 ] || set -- tools
for what in "$@"; do
    case "$what" in
        tools) want_tools=1 ;;
        sumo) want_sumo=1 ;;
        wheel) want_maturin=1 ;;
        libsumo) want_libsumo=1 ;;
        *) echo "python: error: unknown part '$what' (tools, sumo, wheel, libsumo)" >&2; exit 1 ;;
    esac
done
SUMO_PIP_VERSION=${SUMO_PIP_VERSION:-1.28.0}

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

# What is wanted, installed only when it cannot be imported (or is another version).
need=()
if [ $want_tools = 1 ]; then
    "$VENV/bin/python" -c 'import maturin' 2>/dev/null || need+=("maturin>=1.9.4,<2")
    "$VENV/bin/python" -c 'import pytest' 2>/dev/null || need+=("pytest>=7")
    "$VENV/bin/python" -c 'import ray' 2>/dev/null || need+=("ray>=2.9")
    "$VENV/bin/python" -c 'import gymnasium' 2>/dev/null || need+=("gymnasium>=1.0")
    "$VENV/bin/python" -c 'import pettingzoo' 2>/dev/null || need+=("pettingzoo>=1.24")
fi
if [ $want_maturin = 1 ]; then
    "$VENV/bin/python" -c 'import maturin' 2>/dev/null || need+=("maturin>=1.9.4,<2")
fi
if [ $want_libsumo = 1 ]; then
    [ -n "${LIBSUMO_VERSION:-}" ] || die "LIBSUMO_VERSION is not set (the SUMO version bkpbs is built against)"
    have=$("$VENV/bin/python" -c 'import importlib.metadata as m; print(m.version("libsumo"))' 2>/dev/null || true)
    [ "$have" = "$LIBSUMO_VERSION" ] || need+=("libsumo==$LIBSUMO_VERSION")
fi
if [ $want_sumo = 1 ]; then
    have=$("$VENV/bin/python" -c 'import importlib.metadata as m; print(m.version("eclipse-sumo"))' 2>/dev/null || true)
    [ "$have" = "$SUMO_PIP_VERSION" ] || need+=("eclipse-sumo==$SUMO_PIP_VERSION")
fi
if [ ${#need[@]} -gt 0 ]; then
    say "installing ${need[*]} into $VENV (pip)"
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "${need[@]}" \
        || die "pip install ${need[*]} failed (no network to PyPI?)"
fi
exit 0
