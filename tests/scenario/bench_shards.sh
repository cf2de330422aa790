#!/usr/bin/env bash
# colorfree bench: shards 0/3, 1/3, 2/3 merged give the same results.json as one unsharded run
# (with two worker processes), leaving out only the wall-clock timing fields; a missing shard is
# an error that names the missing item.
set -u
bin="$1"; compare="$2"; here="$3"; out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
# The unsharded run's printed tables have a line matching the extended regex $1, else fail with $2.
printed() { grep -Eq "$1" "$out/whole.log" || fail "$2: $(cat "$out/whole.log")"; }
list="$here/bench_small.yaml"

"$bin" bench --list "$list" --jobs 2 --out "$out/whole" >"$out/whole.log" 2>&1 || fail "unsharded run: $(cat "$out/whole.log")"
for i in 0 1 2; do
  "$bin" bench --list "$list" --shard "$i/3" --out "$out/s$i" >"$out/s$i.log" 2>&1 || fail "shard $i/3: $(cat "$out/s$i.log")"
  [ -s "$out/s$i/shard_${i}_of_3.json" ] || fail "shard $i/3 wrote no shard file"
  [ ! -e "$out/s$i/results.json" ] || fail "a shard wrote a results.json that looks complete"
done
"$bin" merge "$out/s0" "$out/s1" "$out/s2" --out "$out/merged" >"$out/merge.log" 2>&1 || fail "merge: $(cat "$out/merge.log")"
[ -s "$out/merged/report.html" ] || fail "merge wrote no report.html"
"$compare" "$out/whole/results.json" "$out/merged/results.json" || fail "sharded and unsharded results differ"
grep -q '"frames": 21' "$out/merged/results.json" || fail "merged results do not count 21 frames"
printed "^  hard +2 .*field_features.line_detection_rate >= 1.01$" \
  "the bench's hard-set table does not list the scenario's unmet expectation"
grep -q '"unmet": \[' "$out/merged/results.json" || fail "merged results have no hard-set summary"
# The sweep's table charts its first swept path (the light scale's four values; the noise, which
# sorts first among the settings, averaged over): each detector's rate per value and the filtered
# orientation's perceived share, then its false share, the robots' false positives per frame and
# the detected robots' and balls' mean position errors in metres (one number per light scale).
printed "^  sweep \(lighting.scale\):$" \
  "the sweep table does not chart the first swept path"
printed "^    orientation( +[0-9]+\.[0-9]{2}){4}   " \
  "the sweep table has no row of the orientation's perceived share"
printed "^    ori false( +([0-9]+\.[0-9]{2}|absent)){4}$" \
  "the sweep table has no row of the orientation's false share"
printed "^    robot FP/f( +[0-9]+\.[0-9]{2}){4}$" \
  "the sweep table has no row of robot false positives per frame"
printed "^    robot err m( +([0-9]+\.[0-9]{3}|absent)){4}$" \
  "the sweep table has no row of robot position errors"
printed "^    ball err m( +([0-9]+\.[0-9]{3}|absent)){4}$" \
  "the sweep table has no row of ball position errors"

"$bin" merge "$out/s0" "$out/s2" --out "$out/partial" >"$out/partial.log" 2>&1
rc=$?
[ "$rc" -eq 2 ] || fail "merge with a missing shard: exit $rc, expected 2"
grep -q "is missing" "$out/partial.log" || fail "missing shard not named: $(cat "$out/partial.log")"
[ ! -e "$out/partial/results.json" ] || fail "results.json written from a partial set of shards"
echo "ok"
