#!/usr/bin/env bash
# Regenerates the networks from their plain XML sources (NAME.nod.xml, NAME.edg.xml,
# NAME.con.xml) with netconvert:
#   merge.net.xml       No internal junction lanes, and zero-width junction shapes, so that every lane
#                       starts and ends exactly at its nodes: the road frame's s equals SUMO's x on the
#                       main road.
#   three-lane.net.xml  netconvert's defaults: internal junction lanes, default junction shapes.
#   corridor.net.xml    netconvert's defaults: internal junction lanes, default junction shapes.
#   layouts/NAME/NAME.net.xml
#                       the merge layouts (README.md), netconvert's defaults, as the tests build them.
# netconvert writes the time of the run into the header comment of each file; a net that comes out
# the same apart from that line keeps its existing file, so rebuilding unchanged sources changes
# nothing.
set -euo pipefail
cd "$(dirname "$0")"
export SUMO_HOME="${SUMO_HOME:-/usr/share/sumo}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# build NAME [OPTION...]: netconvert NAME's plain XML sources into NAME.net.xml with the options.
build() {
    local name=$1
    shift
    local old=$tmp/$name.net.xml
    if [[ -f $name.net.xml ]]; then
        cp "$name.net.xml" "$old"
    fi
    netconvert \
        --node-files "$name.nod.xml" \
        --edge-files "$name.edg.xml" \
        --connection-files "$name.con.xml" \
        "$@" \
        --output-file "$name.net.xml"
    if [[ -f $old ]] && cmp -s <(grep -v '^<!-- generated on ' "$old") \
        <(grep -v '^<!-- generated on ' "$name.net.xml"); then
        cat "$old" >"$name.net.xml"
    fi
}

build merge \
    --offset.disable-normalization true \
    --no-turnarounds true \
    --no-internal-links true
build three-lane
build corridor
for dir in layouts/*/; do
    name=$(basename "$dir")
    (cd "$dir" && build "$name" --no-warnings)
done
