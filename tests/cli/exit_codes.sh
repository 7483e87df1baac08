#!/usr/bin/env bash
# End-to-end check of the `incision` command line: bad input exits 2 with a message naming file, key, reason.
set -u
exe="$1"; tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
fails=0
expect() {  # expect CODE PATTERN -- command...
  local code="$1" pattern="$2"; shift 3
  local out; out="$("$@" 2>&1)"; local rc=$?
  if [ "$rc" != "$code" ] || ! grep -qE -- "$pattern" <<<"$out"; then
    echo "FAIL: '$*' gave rc=$rc (want $code), output: $out (want /$pattern/)"; fails=$((fails + 1))
  else
    echo "ok: $* -> rc=$rc"
  fi
}
printf '{"geometry":{"kind":"box"},"models":{"mls":true},"material":{"poisson_ratio":0.7}}' >"$tmp/nu.json"
printf '{"geometry":{"kind":"box"},\n "models":{"mls":true},,}' >"$tmp/syntax.json"
printf '{"geometry":{"kind":"box"},"models":{"mls":true},"solver":{"frame_dt":0.01}}' >"$tmp/typo.json"
printf '{"geometry":{"kind":"mesh","mesh":"missing.obj"},"models":{"mls":true}}' >"$tmp/mesh.json"
# Haptics: the second device's missing trajectory names its key path; a BEM organ held nowhere, or far from the
# tissue plane (found only when the run builds the model), names haptics.global_mesh.
printf 'v 0 0 0\nv 0.01 0 0\nv 0.01 0.01 0\nv 0 0.01 0\nv 0 0 0.01\nv 0.01 0 0.01\nv 0.01 0.01 0.01\nv 0 0.01 0.01\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n' >"$tmp/organ.obj"
printf '{"geometry":{"kind":"box","center_m":[0.005,0.005,0.005],"size_m":[0.01,0.01,0.01],"spacing_m":0.002},"models":{"mls":true,"haptics":true},"haptics":{"devices":[{"device":"udp","udp_port":47311},{"trajectory":"missing.traj"}]}}' >"$tmp/hands.json"
printf '{"geometry":{"kind":"box","center_m":[0.005,0.005,0.005],"size_m":[0.01,0.01,0.01],"spacing_m":0.002},"models":{"mls":true,"haptics":true},"haptics":{"device":"udp","udp_port":47312,"global_model":"bem","global_mesh":"organ.obj"}}' >"$tmp/unheld.json"
printf '{"geometry":{"kind":"box","center_m":[0.005,0.005,0.005],"size_m":[0.01,0.01,0.01],"spacing_m":0.002},"models":{"mls":true,"haptics":true},"fixed":[{"min_m":[-1,-1,-1],"max_m":[1,1,0.001]}],"haptics":{"device":"udp","udp_port":47313,"surface_point_m":[1,1,1],"global_model":"bem","global_mesh":"organ.obj","global_cache":"far.bemcache"}}' >"$tmp/far.json"
expect 2 "hands.json: haptics.devices\[1\].trajectory: .*missing.traj" -- "$exe" validate "$tmp/hands.json"
expect 2 "unheld.json: haptics.global_mesh: .*no element centroid lies in a fixed region" -- "$exe" validate "$tmp/unheld.json"
expect 0 "" -- "$exe" validate "$tmp/far.json"
expect 2 "far.json: haptics.global_mesh: .*lies .* from the tissue plane" -- "$exe" run "$tmp/far.json" --backend cpu --steps 1 --out "$tmp/o"
expect 0 "" -- "$exe" validate "$(dirname "$0")/../../scenes/haptic_two_hands.json"
expect 2 "nope.json: .*no such file" -- "$exe" validate "$tmp/nope.json"
# 80,000 nested arrays under geometry once crashed validate and run with SIGSEGV (exit 139).
python3 -c 'import sys; d=80000; sys.stdout.write("{\"geometry\": {\"kind\": \"box\", \"size_m\": " + "["*d + "]"*d + "}}")' >"$tmp/deep.json"
expect 2 "deep.json: geometry.size_m\[0\].*nest deeper than 64 levels" -- "$exe" validate "$tmp/deep.json"
expect 2 "deep.json: geometry.size_m\[0\].*nest deeper than 64 levels" -- "$exe" run "$tmp/deep.json" --out "$tmp/o"
expect 2 "nu.json: material.poisson_ratio: must lie" -- "$exe" validate "$tmp/nu.json"
expect 2 "syntax.json.*line 2" -- "$exe" validate "$tmp/syntax.json"
expect 2 "typo.json: solver.frame_dt: .*frame_dt_s" -- "$exe" validate "$tmp/typo.json"
expect 2 "mesh.json: geometry.mesh" -- "$exe" validate "$tmp/mesh.json"
# 3.9e7 particles (under the loader's 5e7 cap) passed validate, then ran out of memory minutes into the build with a
# message naming neither file nor key: validate and run now refuse it before building, naming the key (a 16 GiB
# budget, as on a small host, so the check does not depend on this machine's memory).
printf '{"geometry":{"kind":"box","size_m":[0.34,0.34,0.34],"spacing_m":0.001},"models":{"mls":true},"fixed":[{"min_m":[-1,-1,-1],"max_m":[1,1,-0.16]}]}' >"$tmp/huge.json"
expect 2 "huge.json: geometry.spacing_m: the scene needs about .* GiB of host memory" -- env INCISION_MEMORY_LIMIT_MIB=16384 "$exe" validate "$tmp/huge.json"
expect 2 "huge.json: geometry.spacing_m: the scene needs about" -- env INCISION_MEMORY_LIMIT_MIB=16384 "$exe" run "$tmp/huge.json" --backend cpu --out "$tmp/o"
# A body far stiffer than its spacing and frame allow (~9e4 substeps a frame, limit 20000): refused at its first
# frame with exit 3 and the keys to change, instead of running for minutes per frame.
printf '{"geometry":{"kind":"box","size_m":[0.04,0.04,0.04],"spacing_m":0.01},"material":{"youngs_modulus_pa":1e11},"models":{"mls":true},"fixed":[{"min_m":[-1,-1,-1],"max_m":[1,1,-0.012]}]}' >"$tmp/stiff.json"
expect 3 "substep_limit.*geometry.spacing_m.*solver.max_substeps" -- "$exe" run "$tmp/stiff.json" --backend cpu --steps 3 --quiet --out "$tmp/o"
expect 2 "--backend" -- "$exe" run --backend quantum --out "$tmp/o"
expect 2 "--precision" -- "$exe" run --precision float16 --out "$tmp/o"
# Run lengths: -1 was the internal "not given" and ran the whole duration; a huge count was clamped and ran on.
expect 2 "--steps: must be a number of frames" -- "$exe" run --steps -1 --out "$tmp/o"
expect 2 "--steps: must be a number of frames" -- "$exe" run --steps 0 --out "$tmp/o"
expect 2 "--steps: must be a number of frames" -- "$exe" run --steps 99999999999999999999 --out "$tmp/o"
expect 2 "--seconds: must be a positive" -- "$exe" run --seconds -1 --out "$tmp/o"
expect 2 "--seconds: .* frames of solver.frame_dt_s" -- "$exe" run --seconds 1e12 --out "$tmp/o"
expect 2 "--cost" -- "$exe" tradeoff --cost sometimes --quick --out "$tmp/t"
expect 2 "--models.*unknown model" -- "$exe" tradeoff --models fem --quick --out "$tmp/t"
expect 0 "beam" -- "$exe" scenes
expect 0 "CUDA backend compiled" -- "$exe" devices
# The viewer on the default scene: a scripted run writes a real picture; without a display (or a build
# without the viewer) it exits 1 and points to `incision run`.
if [ -n "${DISPLAY:-}" ] && ! "$exe" view --frames 1 --screenshot "$tmp/probe.png" 2>&1 | grep -q "no viewer"; then
  expect 0 "" -- "$exe" view --backend cpu --frames 3 --screenshot "$tmp/view.png"
  size=$(stat -c %s "$tmp/view.png" 2>/dev/null || echo 0)
  if [ "$size" -lt 20000 ]; then echo "FAIL: view screenshot missing or blank ($size bytes)"; fails=$((fails + 1));
  else echo "ok: view screenshot $size bytes"; fi
else
  expect 1 "incision run" -- env -u DISPLAY "$exe" view --backend cpu --frames 3
fi
[ "$fails" = 0 ] && echo "all CLI exit-code checks passed" || { echo "$fails CLI check(s) failed"; exit 1; }
