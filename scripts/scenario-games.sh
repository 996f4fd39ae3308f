#!/usr/bin/env bash
# Copies SUMO's shipped game scenarios ($SUMO_HOME/tools/game: the A10KW motorway interchange,
# the ramp weaving section, …) into DIR as a user would bring them, with A10KW's step length
# set to the planners' 0.2 s (it ships with 0.5 s, which bkpbs refuses). Idempotent.
#
#   scripts/scenario-games.sh DIR
set -euo pipefail
dir=${1:?usage: scripts/scenario-games.sh DIR}
sumo_home=${SUMO_HOME:-/usr/share/sumo}
game="$sumo_home/tools/game"
[ -f "$game/A10KW.sumocfg" ] || { echo "scenario-games: error: no SUMO game scenarios in $game (set SUMO_HOME)" >&2; exit 1; }
rm -rf "$dir"
mkdir -p "$(dirname "$dir")"
cp -r "$game" "$dir"
sed -i 's|<step-length value="0.5"/>|<step-length value="0.2"/>|' "$dir/A10KW.sumocfg"
grep -q '<step-length value="0.2"/>' "$dir/A10KW.sumocfg"
