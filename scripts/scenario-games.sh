#!/usr/bin/env bash
# Copies SUMO's shipped game scenarios ($SUMO_HOME/tools/game: the A10KW motorway interchange,
# the ramp weaving section, …) into DIR as a user would bring them, with A10KW's step length
# set to the planners' 0.2 s (it ships with 0.5 s, which bkpbs refuses). Idempotent.
#
# Also A10KW-motorway.sumocfg: A10KW's motorway alone, with SUMO's own tools — netconvert keeps
# the edges of types highway.motorway and highway.motorway_link, duarouter routes the game's
# two flows (extra.rou.xml, from side streets onto the ramps), and cutRoutes.py cuts every
# route of the seven route files to that network, each vehicle departing where its route enters
# it at the time its free-flow drive from its origin would bring it there (--orig-net). In the
# full game the streets feeding the two on-ramps jam, and the merges see almost no ramp traffic
# (2 and 0 vehicles in 30 min under every planner, SUMO alone included); on the motorway alone
# every vehicle of those routes reaches them. It runs the game's first 15 minutes (its <end> 900
# instead of 1800 s: the planners' episodes there take minutes each). The tools' "generated on"
# comments are removed, so that the same SUMO gives the same files.
#
#   scripts/scenario-games.sh DIR
set -euo pipefail
dir=${1:?usage: scripts/scenario-games.sh DIR}
export SUMO_HOME=${SUMO_HOME:-/usr/share/sumo}
game="$SUMO_HOME/tools/game"
[ -f "$game/A10KW.sumocfg" ] || { echo "scenario-games: error: no SUMO game scenarios in $game (set SUMO_HOME)" >&2; exit 1; }
rm -rf "$dir"
mkdir -p "$(dirname "$dir")"
cp -r "$game" "$dir"
sed -i 's|<step-length value="0.5"/>|<step-length value="0.2"/>|' "$dir/A10KW.sumocfg"
grep -q '<step-length value="0.2"/>' "$dir/A10KW.sumocfg"

# A10KW's motorway alone.
a10="$dir/A10KW"
mw="$dir/A10KW-motorway"
mkdir -p "$mw"
netconvert --no-warnings -s "$a10/osm.net.xml" --keep-edges.by-type highway.motorway,highway.motorway_link \
    -o "$mw/motorway.net.xml" >/dev/null
duarouter --no-step-log --no-warnings -n "$a10/osm.net.xml" -r "$a10/extra.rou.xml" \
    -o "$mw/extra.routed.rou.xml" >/dev/null
routes=""
for f in osm.passenger osm.truck osm.passenger_mw osm.truck_mw osm.passenger_mwb osm.truck_mwb; do
    routes="$routes $a10/$f.rou.xml"
done
# shellcheck disable=SC2086
python3 "$SUMO_HOME/tools/route/cutRoutes.py" "$mw/motorway.net.xml" $routes "$mw/extra.routed.rou.xml" \
    --orig-net "$a10/osm.net.xml" -o "$mw/motorway.rou.xml" >/dev/null
rm -f "$mw/extra.routed.rou.xml" "$mw"/*.alt.xml
# The tools' header comments name the date and the input paths.
for f in "$mw/motorway.net.xml" "$mw/motorway.rou.xml"; do
    python3 - "$f" <<'PY'
import re, sys
path = sys.argv[1]
text = open(path, encoding="utf-8").read()
text = re.sub(r"<!-- generated on .*?-->\n*", "", text, count=1, flags=re.S)
open(path, "w", encoding="utf-8").write(text)
PY
done
sed -e 's|A10KW/osm.net.xml|A10KW-motorway/motorway.net.xml|' \
    -e 's|<route-files value="[^"]*"/>|<route-files value="A10KW-motorway/motorway.rou.xml"/>|' \
    -e 's|<additional-files value="[^"]*"/>||' \
    -e 's|<end value="1800"/>|<end value="900"/>|' \
    "$dir/A10KW.sumocfg" > "$dir/A10KW-motorway.sumocfg"
grep -q 'A10KW-motorway/motorway.rou.xml' "$dir/A10KW-motorway.sumocfg"
grep -q '<end value="900"/>' "$dir/A10KW-motorway.sumocfg"
