#!/usr/bin/env bash
# run_resume.sh DRIVER PRM MPIEXEC...: run PRM with the driver (under
# MPIEXEC...) once straight through (in ./straight) and once stopped after
# 120 steps and resumed from the checkpoint at step 100 (in ./resumed); the
# final node tables must agree exactly, and bonds must break beyond the
# pre-crack during the run (CSV column broken_bonds grows).
set -euo pipefail
driver="$1"; prm="$2"; shift 2
rm -rf straight resumed && mkdir straight resumed
(cd straight && "$@" "$driver" "$prm")
(cd resumed && "$@" "$driver" --stop-after-steps 120 "$prm" && "$@" "$driver" --resume "$prm")
"$driver" --compare straight/output/nodes.csv resumed/output/nodes.csv 0
awk -F, 'NR == 2 { first = $5 } END { last = $5; print "broken bonds: " first " -> " last;
         exit !(last > first) }' straight/output/time_series.csv
