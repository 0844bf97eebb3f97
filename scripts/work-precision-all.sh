#!/usr/bin/env bash
# Regenerates every committed work–precision study with the REBOUND rows merged in:
# Kepler T = 200 (docs/studies/work_precision.*), Kepler T = 20 000
# (docs/studies/work-precision-long/), the outer solar system
# (docs/studies/work-precision-outer-solar-system/) and the J2000 10-body scene
# (docs/studies/work-precision-solar-system/). Run it on a quiet machine: every timing is
# wall-clock, one configuration after another. About 8 minutes on a 2-core machine
# (REBOUND 5.2.2 runs and the economical and compact families included).
#
# Needs the REBOUND venv: python3 -m venv .venv-rebound &&
#   .venv-rebound/bin/pip install -r scripts/rebound/requirements.txt
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p galerkin-vi-lab
GVI=target/release/gvi
PY=.venv-rebound/bin/python
S=scripts/rebound/work_precision.py
E=docs/studies/external
# Each scene's REBOUND runs come right before its own study, so that both see the same load on
# a shared machine; `uptime` before and after each scene goes to stderr.
rebound() {
  if [ "${SKIP_REBOUND:-0}" != 1 ]; then $PY $S "$@"; fi
}
uptime >&2
rebound kepler --repeats 5 --out $E/rebound-kepler-T200.csv
$GVI work-precision kepler --external $E/rebound-kepler-T200.csv --out docs/studies
uptime >&2
rebound kepler --horizon 20000 --out $E/rebound-kepler-T20000.csv
$GVI work-precision kepler --long --external $E/rebound-kepler-T20000.csv \
  --out docs/studies/work-precision-long
uptime >&2
rebound outer-solar-system --repeats 5 --out $E/rebound-outer-solar-system.csv
$GVI work-precision outer-solar-system --repeats 3 --bases chebyshev,legendre \
  --ns 6,8,10,12,14,16,20,24 --divisors 1,2,3,4,6 \
  --external $E/rebound-outer-solar-system.csv --out docs/studies/work-precision-outer-solar-system
uptime >&2
rebound solar-system --repeats 5 --out $E/rebound-solar-system.csv
# J2000: n and h on a finer grid near the 1e-9 frontier (n = 9, 11, 14; h = Δ/5, Δ/7, Δ/9,
# Δ/10), as REBOUND's fixed-step families are swept over 33 divisors.
# The Kepler-adapted families: s up to 10 and h = Δ/5 as well, near the frontier of the
# family with Mercury alone on its Kepler orbit (galerkin-kepler-S-fast).
$GVI work-precision solar-system --repeats 3 --bases chebyshev,legendre \
  --ns 8,9,10,11,12,14,16,20,25,32 --divisors 1,2,4,5,6,7,8,9,10 \
  --kepler-stages 6,8,9,10 --kepler-divisors 2,3,4,5,6,8 \
  --external $E/rebound-solar-system.csv --out docs/studies/work-precision-solar-system
uptime >&2
python3 scripts/work-precision-summary.py > docs/studies/work-precision-summary.md
