#!/usr/bin/env bash
# The platform gap (docs/study/layers.md "The platform gap"): the first two passes of the shipped
# machine point (sweeps/ti64-layers.toml at 50 µm and 0.1 m/s) as the deck has them — the round
# blade a largest diameter over the feed platform and the wall — and with those two raised to the
# blade's tip line (no gap, as the layout had it before). Prints, after each pass, the particles
# pressed into the feed platform (centre under its top face), LIGGGHTS's neighbour-list builds
# and CPU seconds of the blade's crossing, and the mass on the plate. About 10 CPU minutes.
# Run from the repository's root with target/release/sweep built (or SWEEP=path).
set -euo pipefail
cd "$(dirname "$0")/../../.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"${SWEEP:-target/release/sweep}" render sweeps/ti64-layers.toml \
  --set layer_thickness=0.05,blade_speed=0.1 --out "$tmp/gap" > /dev/null
cp -r "$tmp/gap" "$tmp/nogap"
for case in gap nogap; do
  deck="$tmp/$case/in.liggghts"
  x0=$(awk '/^region feedside/ {print $5}' "$deck")
  # Keep passes 1–2; after each pass's count line, count what lies inside the feed platform.
  awk -v nogap=$([ $case = nogap ] && echo 1 || echo 0) -v x0="$x0" '
    /^# ---- Pass 3:/ { exit }
    /^# ---- Pass [0-9]+:/ { top = $8; tip = $14 }
    nogap && /file (feed|wall)\.stl/ { sub(/move 0 0 .*/, "move 0 0 " tip) }
    /^print "demsweep: layer/ {
      k++; face = nogap ? tip : top
      print "region sunk" k " block INF " x0 " INF INF INF " face " units box"
      print "variable sunk" k " equal count(powder,sunk" k ")"
      print "print \"platform-gap: pass " k ": ${sunk" k "} particles inside the feed platform, plate mass ${platemass} kg\""
    }
    { print }' "$deck" > "$deck.two"
  mv "$deck.two" "$deck"
  (cd "$tmp/$case" && liggghts -in in.liggghts -log log.liggghts -echo none -nocite > /dev/null)
  echo "== $case"
  grep '^platform-gap' "$tmp/$case/log.liggghts"
  # The blade's crossings are the runs of pass_steps (the longest runs of a pass).
  awk '/^Loop time of/ {t = $4; n = $9} /^Neighbor list builds/ {if (n > 80000) printf "crossing of %d steps: %.0f CPU s, %s neighbour-list builds\n", n, t, $5}' \
    "$tmp/$case/log.liggghts"
done
