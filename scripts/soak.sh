#!/usr/bin/env bash
# make soak: plays simulated bags (a 400k-ray laser scan and a 640x480 RGB-D
# frame, in turn) in a loop through the door-state nodelet at 10 Hz, through
# tf (~fixed_frame map), for SOAK_SECONDS (default 600), and reports clouds
# published, processed and dropped, latency percentiles and the nodelet
# manager's resident memory at start, after the first cloud, every tenth of
# the run and at the end. Exit 1 when the nodelet stopped answering.
#
#   SOAK_SECONDS=600 scripts/soak.sh
#
# The work is done by scripts/nodelet_latency.sh (case `soak`); figures also
# in $DSR_BUILD/latency/soak.json, logs in $DSR_BUILD/latency/.
set -euo pipefail
REPO="$(cd "$(dirname "$0")/.." && pwd)"
export SOAK_SECONDS="${SOAK_SECONDS:-600}"
exec "$REPO/scripts/nodelet_latency.sh" soak
