#!/usr/bin/env bash
# Redraws the pictures of the viewer and of the demo report in docs/img:
#
#   viewer.png               et view, the simulated sheet pressed at (30, 25) mm
#   viewer-model.png         the same with et demo's 49-class model (the class lit)
#   viewer-replay.png        et view --replay of the swipe recording (et sim)
#   viewer-two.png           et view --scene sim/scenes/disc-ref-two.toml (two touches)
#   report-x050-ad.png       et demo: one touch at x = 0.5, adjacent protocol
#   report-two-pp-pp.png     et demo: two touches, PP-PP
#   report-error-vs-distance.png   et demo: the model's error against distance
#
#   ./scripts/pictures.sh        # 72 s after the release build (2-core development VM, 2026-11-25)
#
# The viewer runs in a real window under Xvfb (Debian's xvfb: `apt install xvfb`); each
# screenshot is taken once V_0 is in and the press (if any) shows, then the window closes.
# Look at every picture after running this: it is what the README and the guide show.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v xvfb-run >/dev/null; then
  echo "pictures: needs xvfb-run (apt install xvfb)" >&2
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "== building et (release, with the viewer)"
cargo build --release -q -p et-host --features viewer --bin et
et=target/release/et

echo "== et demo (its model and its figures)"
"$et" demo --out "$work/report" >/dev/null
"$et" sim --scene sim/scenes/square-13cm-16-swipe.toml --frames 300 --out "$work/session.jsonl" \
  >/dev/null

root=$PWD
shot() { # shot NAME.png [et view arguments], run in the work directory (short paths)
  local png=$root/docs/img/$1
  shift
  echo "== docs/img/$(basename "$png"): et view $*"
  (cd "$work" && timeout 180 xvfb-run -a -s "-screen 0 1280x800x24" \
    "$root/$et" view "$@" --screenshot "$png" --force)
  test -s "$png"
}
shot viewer.png --press 30,25
shot viewer-model.png --model report/learning/model.json --press 30,25
shot viewer-replay.png --replay session.jsonl
cp sim/scenes/disc-ref-two.toml "$work/"
shot viewer-two.png --scene disc-ref-two.toml

echo "== the report's figures"
cp "$work/report/imaging/disc-ref-x050-adjacent.png" docs/img/report-x050-ad.png
cp "$work/report/imaging/disc-ref-two-pp-pp.png" docs/img/report-two-pp-pp.png
cp "$work/report/learning/error-vs-distance.png" docs/img/report-error-vs-distance.png
echo "pictures: 7 written in docs/img; look at each"
