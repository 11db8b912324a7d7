#!/usr/bin/env bash
# Drives the real MeshLab GUI (private prefix) on the current X display:
#   gui_session.sh OUT_DIR MESH
# Writes OUT_DIR/plugins.txt (the MeshMend plugin files the GUI process has
# loaded), OUT_DIR/search.png (the filter search listing "MeshMend" filters),
# OUT_DIR/menu.png (Filters > Quality Measure and Computations open) and
# OUT_DIR/alive (the GUI survived). Run it under xvfb-run.
set -uo pipefail
out=$1 mesh=$2
root="$(cd "$(dirname "$0")/../.." && pwd)"
mkdir -p "$out"
"$root/scripts/meshlab" "$mesh" >"$out/meshlab.log" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null' EXIT
for _ in $(seq 60); do
  xdotool search --onlyvisible --name "^MeshLab 20" >/dev/null 2>&1 && break
  sleep 0.5
done
sleep 2  # let the first frame render
gui=$(pgrep -P $pid -f "bin/meshlab" || echo $pid)  # the wrapper execs, so usually $pid itself
grep -o '[^/]*mend_[^/]*\.so' "/proc/$gui/maps" 2>/dev/null | sort -u >"$out/plugins.txt"

xdotool mousemove 832 46 click 1; sleep 0.8    # the filter search (magnifier)
xdotool type --delay 40 "MeshMend"; sleep 1.5
import -window root "$out/search.png"
xdotool key Escape; sleep 0.3; xdotool key Escape; sleep 0.3

xdotool mousemove 120 10 click 1; sleep 1          # the Filters menu
xdotool mousemove 245 262 click 1; sleep 1.2       # Quality Measure and Computations
import -window root "$out/menu.png"
xdotool key Escape; sleep 0.2; xdotool key Escape

kill -0 $pid 2>/dev/null && touch "$out/alive"
