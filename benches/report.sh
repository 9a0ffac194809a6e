#!/usr/bin/env bash
# Runs the benchmarks (bulk assembly, Newton steps, contact search, mortar pair integration)
# and prints one compact table of the results.
#
#   benches/report.sh [CRITERION OPTIONS...]
#
# e.g. `benches/report.sh --warm-up-time 1 --measurement-time 3`, or a name filter such as
# `benches/report.sh hex8`. Criterion's own output goes to stderr; the table goes to stdout.
#
# Columns: the time of one benchmark iteration (criterion's estimate: the slope of the linear
# fit if it has one, else the mean, with its 95% interval); where a benchmark counts items
# (criterion's throughput: elements for the assembly, secondary segments for the search, face
# pairs for the mortar kernels) the items per second and the time per item; for the Newton-step
# benchmarks the Newton iterations of the step (the `newton-its` lines the bench prints) and the
# time per Newton iteration (step time / iterations, everything in the step included).
#
# Only the benchmarks run by this invocation are listed (read from
# target/criterion/<id>/new/{benchmark,estimates}.json).
set -euo pipefail

cd "$(dirname "$0")/.."
log=$(mktemp)
trap 'rm -f "$log"' EXIT

cargo bench --bench assembly --bench newton --bench search --bench mortar -- --noplot "$@" 2>&1 | tee "$log" >&2

target=$(cargo metadata --format-version 1 --no-deps |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')

python3 - "$target/criterion" "$log" <<'EOF'
import json
import os
import re
import sys

root, log_path = sys.argv[1], sys.argv[2]
with open(log_path, encoding="utf-8", errors="replace") as f:
    log = f.read()

# Benchmarks of this run, in the order they ran, and the Newton iterations the bench reported.
ran = list(dict.fromkeys(re.findall(r"^Benchmarking (\S+): Analyzing", log, re.M)))
newton_its = {m[0]: int(m[1]) for m in re.findall(r"^newton-its (\S+) (\d+)", log, re.M)}

# full_id -> (benchmark.json, estimates.json) of the latest run.
results = {}
for d, _, files in os.walk(root):
    if os.path.basename(d) == "new" and {"benchmark.json", "estimates.json"} <= set(files):
        with open(os.path.join(d, "benchmark.json")) as f:
            bench = json.load(f)
        with open(os.path.join(d, "estimates.json")) as f:
            est = json.load(f)
        results[bench["full_id"]] = (bench, est)


def fmt_time(ns):
    for unit, scale in (("s", 1e9), ("ms", 1e6), ("us", 1e3)):
        if ns >= scale:
            return f"{ns / scale:.3g} {unit}"
    return f"{ns:.3g} ns"


def fmt_rate(per_s):
    for unit, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if per_s >= scale:
            return f"{per_s / scale:.3g} {unit}/s"
    return f"{per_s:.3g} /s"


rows = []
for full_id in ran:
    if full_id not in results:
        continue
    bench, est = results[full_id]
    typical = est.get("slope") or est["mean"]
    ns = typical["point_estimate"]
    lo = typical["confidence_interval"]["lower_bound"]
    hi = typical["confidence_interval"]["upper_bound"]
    row = [full_id, fmt_time(ns), f"{fmt_time(lo)} .. {fmt_time(hi)}", "", "", "", ""]
    elements = (bench.get("throughput") or {}).get("Elements")
    if elements:
        row[3] = fmt_rate(elements / (ns * 1e-9))
        row[4] = fmt_time(ns / elements)
    its = newton_its.get(full_id)
    if its:
        row[5] = str(its)
        row[6] = fmt_time(ns / its)
    rows.append(row)

if not rows:
    sys.exit("report.sh: no benchmark results found in this run")
header = ["benchmark", "time/iter", "95% interval", "items/s", "time/item", "newton its",
          "time/newton it"]
widths = [max(len(r[i]) for r in rows + [header]) for i in range(len(header))]
for r in [header, ["-" * w for w in widths]] + rows:
    print("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())
EOF
