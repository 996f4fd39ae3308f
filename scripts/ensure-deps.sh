#!/usr/bin/env bash
# Installs what bkpbs needs on a Debian machine, only if missing (idempotent):
# SUMO with libsumo's C++ library and headers (Debian packages sumo, sumo-tools), a C++ compiler,
# the DejaVu font for report figures (fonts-dejavu-core), a virtual X server for the sumo-gui
# test (xvfb, xauth), and a Rust toolchain check. Fails with
# one clear line when something cannot be had.
set -euo pipefail

say() { echo "setup: $*" >&2; }
die() { echo "setup: error: $*" >&2; exit 1; }

need_apt=()
have_libsumo() { [ -f /usr/include/libsumo/libsumo.h ] && compgen -G "/usr/lib/*/libsumocpp.so" >/dev/null; }
have_libsumo || need_apt+=(sumo)
command -v netconvert >/dev/null 2>&1 || need_apt+=(sumo)
[ -d /usr/share/sumo/tools ] || need_apt+=(sumo-tools)
command -v c++ >/dev/null 2>&1 || need_apt+=(g++)
command -v make >/dev/null 2>&1 || need_apt+=(make)
# The font of the campaign report's figures (read at run time; no fontconfig needed).
[ -f /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] || need_apt+=(fonts-dejavu-core)
# A virtual X server, so that the test of `episode --gui` (sumo-gui) runs without a display.
command -v xvfb-run >/dev/null 2>&1 || need_apt+=(xvfb)
command -v xauth >/dev/null 2>&1 || need_apt+=(xauth)

if [ ${#need_apt[@]} -gt 0 ]; then
    pkgs=$(printf '%s\n' "${need_apt[@]}" sumo sumo-tools | sort -u | tr '\n' ' ')
    command -v apt-get >/dev/null 2>&1 || die "missing ${pkgs}and no apt-get: install SUMO 1.15+ with libsumo (C++ library and headers) by hand"
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null 2>&1 || die "missing ${pkgs}: run as root or install sudo"
        SUDO="sudo -n"
    fi
    say "installing ${pkgs}(apt-get)"
    export DEBIAN_FRONTEND=noninteractive
    $SUDO apt-get update -qq >/dev/null || die "apt-get update failed"
    # shellcheck disable=SC2086
    $SUDO apt-get install -y -qq $pkgs >/dev/null || die "apt-get install $pkgs failed"
fi
have_libsumo || die "SUMO is installed but libsumo (libsumocpp.so and /usr/include/libsumo) is missing: need Debian's sumo package, 1.15+"

command -v cargo >/dev/null 2>&1 || die "cargo not found: install a Rust toolchain (1.85 or newer), e.g. with rustup"
exit 0
