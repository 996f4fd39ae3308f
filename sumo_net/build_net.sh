#!/usr/bin/env bash
# Regenerates merge.net.xml from the plain XML sources with netconvert.
# No internal junction lanes, and zero-width junction shapes, so that every lane starts and ends
# exactly at its nodes: the road frame's s equals SUMO's x on the main road.
set -euo pipefail
cd "$(dirname "$0")"
export SUMO_HOME="${SUMO_HOME:-/usr/share/sumo}"
netconvert \
    --node-files merge.nod.xml \
    --edge-files merge.edg.xml \
    --connection-files merge.con.xml \
    --offset.disable-normalization true \
    --no-turnarounds true \
    --no-internal-links true \
    --output-file merge.net.xml
