#!/usr/bin/env bash
# Usage: check_summary.sh SUMMARY TOL COMMAND...
# Run COMMAND, then check in SUMMARY (key: value lines) that the reaction
# force on the prescribed nodes balances the total body force,
# |reaction_force_c + body_force_c| <= TOL * max_c |body_force_c|, and that
# the strain energy is positive.
set -u
summary="$1"; tol="$2"; shift 2
"$@" || exit 1
[ -f "$summary" ] || { echo "no $summary"; exit 1; }
cat "$summary"
awk -v tol="$tol" -F': ' '
  /^reaction_force_/ { c = substr($1, 16); r[c] = $2 }
  /^body_force_/     { c = substr($1, 12); b[c] = $2; m = (($2 < 0 ? -$2 : $2) > m) ? ($2 < 0 ? -$2 : $2) : m }
  /^strain_energy/   { e = $2 }
  END {
    bad = (e <= 0) || (length(r) == 0)
    for (c in r) { d = r[c] + b[c]; if (d < 0) d = -d; printf "component %s: |R + B| = %g\n", c, d; if (d > tol * m) bad = 1 }
    if (bad) { print "FAIL: reaction does not balance the body force or energy <= 0"; exit 1 }
    print "ok: reaction balances body force"
  }' "$summary"
