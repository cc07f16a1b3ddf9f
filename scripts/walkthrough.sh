#!/usr/bin/env bash
# Runs every README command that needs no hardware, as written, from the repository's root,
# then every example of docs/guide.md that needs no hardware (scripts/doc_blocks.py reads them
# from the guide itself), and prints how long each took (the README's times come from this
# script's output).
#
#   ./scripts/walkthrough.sh            # about 5 minutes after the release build
#
# `et` is what the README says it stands for: `cargo run --release -p et-host --bin et --`.
# The files the README's commands write (et-demo-report/, session.jsonl, f80.png, train.csv,
# model.json, nextday.csv, plots/, model.etm, F.csv, T.csv, m.json, own-plots/) are written
# where the README says, in the repository's root; the script refuses to start if any of them
# exists (so nothing of yours is replaced) and removes them at the end (KEEP=1 keeps them).
# `et view` runs under Xvfb (Debian's xvfb) for a few seconds when xvfb-run is installed, as
# the README writes it: `et` with `--features viewer`.
# Commands that need a board (et record/upload/stream --port, the training wizard, flashing
# the firmware) are not run here: tests/tests/qemu.rs runs the same commands' code against the
# firmware image in QEMU over a pseudo-terminal.
set -euo pipefail
cd "$(dirname "$0")/.."

outputs=(et-demo-report session.jsonl f80.png train.csv model.json nextday.csv plots model.etm
  F.csv T.csv m.json own-plots)
for f in "${outputs[@]}"; do
  if [ -e "$f" ]; then
    echo "walkthrough: $f exists in the repository's root; move it away first" >&2
    exit 1
  fi
done
cleanup() {
  if [ "${KEEP:-0}" != 1 ]; then rm -rf "${outputs[@]}"; fi
}
trap cleanup EXIT

et() { cargo run --release -q -p et-host --bin et -- "$@"; }
etv() { cargo run --release -q -p et-host --features viewer --bin et -- "$@"; }
ran=0
run() { # run "command as the README writes it"
  local started=$SECONDS
  printf '\n$ %s\n' "$1"
  eval "$1"
  printf '  (%d s)\n' $((SECONDS - started))
  ran=$((ran + 1))
}
# A window: opened under Xvfb and left for a few seconds (still running then means it opened).
window() {
  if ! command -v xvfb-run >/dev/null; then
    printf '\n$ %s\n  (skipped: no xvfb-run; apt install xvfb)\n' "$1"
    return
  fi
  printf '\n$ %s   # under Xvfb for 8 s\n' "$1"
  local status=0
  timeout 8 xvfb-run -a -s "-screen 0 1280x800x24" bash -c "$(declare -f etv); et() { etv \"\$@\"; }; $1" \
    || status=$?
  if [ "$status" -ne 124 ]; then
    echo "walkthrough: '$1' ended with status $status before its window could be used" >&2
    exit 1
  fi
  ran=$((ran + 1))
}

echo "== building et (release; with the viewer too when its windows can open)"
cargo build --release -q -p et-host --bin et
if command -v xvfb-run >/dev/null; then cargo build --release -q -p et-host --features viewer --bin et; fi
printf '  (%d s)\n' "$SECONDS"

echo "== the two commands: the main job (the test command is what CI runs)"
run "cargo run --release -p et-host --bin et -- demo"
test -s et-demo-report/index.md && test -s et-demo-report/summary.json

echo "== 2. watch it live"
window "et view"

echo "== 3. record a session"
run "et sim --scene sim/scenes/square-13cm-16-swipe.toml --frames 300 --out session.jsonl"
run "et ports"
window "et view --replay session.jsonl"
run "et reconstruct --scene sim/scenes/square-13cm-16.toml --frames session.jsonl --frame 80 --out f80.png"
run "et stream --json --replay session.jsonl > /dev/null"

echo "== 4. train a model"
run "et collect --scene sim/scenes/square-13cm-16.toml --grid 7x7 --out train.csv"
run "et train --data train.csv --keep 87 --out model.json"
run "et collect --scene sim/scenes/square-13cm-16.toml --grid 7x7 --seed 77 --visits 1 --scans 1 --out nextday.csv"
run "et eval --model model.json --data nextday.csv --plots plots/"

echo "== 5. put it on the board (the blob; uploading needs the board)"
run "et export --model model.json --precision f16 --out model.etm"

echo "== your own sensor's data (the stand-in e-skin table as F.csv and T.csv)"
standin=$(mktemp -d)
cargo run --release -q -p et-learn --example standin -- "$standin" 2500 >/dev/null
mv "$standin/features.csv" F.csv
mv "$standin/targets.csv" T.csv
rm -r "$standin"  # the example also writes before.csv, pressed.csv and sessions.csv
run "et train --features F.csv --targets T.csv --unit m --rows 0..2000 --kind auto --out m.json"
run "et eval  --model m.json --features F.csv --targets T.csv --unit m --rows 2000..2500 --json --plots own-plots/"

readme=$ran
echo "== docs/guide.md's examples, as written, in a scratch folder (with sim/ and python/ beside them)"
root=$PWD
guide=$(mktemp -d)
ln -s "$root/sim" "$guide/sim"
ln -s "$root/python" "$guide/python"
cp F.csv T.csv "$guide/"
examples=$(python3 scripts/doc_blocks.py docs/guide.md "$guide")
(
  cd "$guide"
  et() { cargo run --release -q --manifest-path "$root/Cargo.toml" -p et-host --bin et -- "$@"; }
  eval "$examples"
  echo "$ran" >"$guide/.ran"
)
ran=$(cat "$guide/.ran")
[ "${KEEP:-0}" = 1 ] && echo "(the guide's files are kept in $guide)" || rm -rf "$guide"

printf '\nwalkthrough: %d README commands and %d of docs/guide.md ran as written\n' "$readme" \
  $((ran - readme))
