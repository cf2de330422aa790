#!/usr/bin/env bash
# colorfree run: an unmet expectation exits 1 naming scenario, metric, value and bound; an unknown
# metric exits 2 before rendering and leaves no results.json.
set -u
bin="$1"; here="$2"; out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$bin" run "$here/tiny_unmet.yaml" --out "$out/unmet" --quiet >"$out/unmet.stdout" 2>"$out/unmet.stderr"
rc=$?
[ "$rc" -eq 1 ] || fail "unmet expectation: exit $rc, expected 1"
grep -q "tiny_unmet" "$out/unmet.stderr" || fail "no scenario name in: $(cat "$out/unmet.stderr")"
grep -Eq "ball.detection_rate = ([0-9.]+|absent), expected >= 1.01" "$out/unmet.stderr" || fail "no metric/value/bound in: $(cat "$out/unmet.stderr")"
[ -s "$out/unmet/results.json" ] || fail "no results.json after a completed run"
[ -s "$out/unmet/report.html" ] || fail "no report.html after a completed run"
grep -q '"frame_count": 2' "$out/unmet/results.json" || fail "frame_count is not 2"

"$bin" run "$here/tiny_unknown_metric.yaml" --out "$out/unknown" --quiet >"$out/unknown.stdout" 2>"$out/unknown.stderr"
rc=$?
[ "$rc" -eq 2 ] || fail "unknown metric: exit $rc, expected 2"
grep -q "ball.detecton_rate" "$out/unknown.stderr" || fail "the unknown metric is not named: $(cat "$out/unknown.stderr")"
[ ! -e "$out/unknown/results.json" ] || fail "results.json written for a run that never started"
# --expect replaces the scenario's expectations: a floor that holds passes, one that does not fails
# naming it, and an unknown metric stops before rendering.
"$bin" run "$here/tiny_unmet.yaml" --out "$out/floor" --quiet --expect "ball.proposals_per_frame <= 1000" \
  >/dev/null 2>"$out/floor.stderr"
rc=$?
[ "$rc" -eq 0 ] || fail "--expect that holds: exit $rc, expected 0: $(cat "$out/floor.stderr")"
"$bin" run "$here/tiny_unmet.yaml" --out "$out/floor2" --quiet --expect "ball.proposals_per_frame >= 1000" \
  >/dev/null 2>"$out/floor2.stderr"
rc=$?
[ "$rc" -eq 1 ] || fail "--expect not met: exit $rc, expected 1"
grep -Eq "ball.proposals_per_frame = [0-9.]+, expected >= 1000" "$out/floor2.stderr" || fail "no floor in: $(cat "$out/floor2.stderr")"
"$bin" run "$here/tiny_unmet.yaml" --out "$out/floor3" --quiet --expect "ball.proposals_per_frme >= 1" \
  >/dev/null 2>"$out/floor3.stderr"
rc=$?
[ "$rc" -eq 2 ] || fail "--expect with an unknown metric: exit $rc, expected 2"
echo "ok"
