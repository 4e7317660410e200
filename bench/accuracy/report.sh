#!/bin/sh
# bench/accuracy/report.sh OUT_DIR [SECONDS] — plots (gnuplot, PNG and SVG) and markdown
# tables from OUT_DIR/accuracy.csv and accuracy_summary.csv (written by bench_accuracy
# through run.sh). May be rerun alone on the CSVs.
set -eu
OUT=${1:?usage: report.sh OUT_DIR [SECONDS]}
ELAPSED=${2:-}
CSV=$OUT/accuracy.csv
SUM=$OUT/accuracy_summary.csv
if [ ! -s "$CSV" ] || [ ! -s "$SUM" ]; then echo "report: $CSV or $SUM missing" >&2; exit 1; fi

scenes=$(awk -F, 'NR > 1 && !seen[$1]++ { print $1 }' "$CSV")

if command -v gnuplot >/dev/null 2>&1; then
  for s in $scenes; do
    dat=$OUT/accuracy-$s.dat
    # One gnuplot data block per configuration (columns: spp seconds relmse rmse).
    awk -F, -v s="$s" 'NR > 1 && $1 == s && $4 > 0 {
        if (!($2 in idx)) { idx[$2] = n++; order[n - 1] = $2 }
        rows[$2] = rows[$2] sprintf("%s %s %s %s\n", $4, $5, $6, $7)
      } END { for (i = 0; i < n; i++) printf "# %s\n%s\n\n", order[i], rows[order[i]] }' "$CSV" > "$dat"
    names=$(grep '^# ' "$dat" | cut -c3- | tr '\n' ' ')
    for term in png svg; do
      case $term in
        png) t="pngcairo size 1200,480 font 'sans,10'" ;;
        svg) t="svg size 1200,480 dynamic font 'sans,10'" ;;
      esac
      gnuplot <<EOF
set terminal $t
set output '$OUT/accuracy-$s.$term'
set multiplot layout 1,2 title "$s: relMSE against a reference (log-log)"
set logscale xy
set grid
set key outside right top
set ylabel 'relMSE'
names = "$names"
set xlabel 'wall seconds (cumulative, side by side)'
plot for [i=1:words(names)] '$dat' index (i-1) using 2:3 with linespoints title word(names, i), \
     0.01 with lines dt 2 lc 'gray' title '1%', 0.001 with lines dt 3 lc 'gray' title '0.1%'
set xlabel 'samples per pixel'
unset key
set format x '%g'
plot for [i=1:words(names)] '$dat' index (i-1) using 1:3 with linespoints title word(names, i), \
     0.01 with lines dt 2 lc 'gray' notitle, 0.001 with lines dt 3 lc 'gray' notitle
unset multiplot
EOF
    done
    rm -f "$dat"
  done
else
  echo "report: gnuplot not found; no plots" >&2
fi

{
  echo "# Accuracy against time"
  echo
  cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo 2>/dev/null | head -n 1)
  echo "$(date -u +%Y-%m-%dT%H:%MZ), ${cpu:-unknown CPU}, $(nproc) CPUs, load average" \
       "$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo unknown) at the end${ELAPSED:+; the study took $ELAPSED s}."
  awk -F, 'NR == 2 { printf "Reference: %s spp per scene and integrator.\n", $12 }' "$CSV"
  echo
  echo "t(x): seconds to relMSE x = the spp reaching x (*i* interpolated between measured counts,"
  echo "*e* extrapolated along the fitted spp slope) × ms/spp (fastest of 7 side-by-side timing rounds); ratio = t ÷ t of"
  echo "the scene's \`base\`. Slopes: log relMSE against log spp and log seconds, counts ≥ 4 spp;"
  echo "MSE slope: log RMSE² against log spp; trimmed: relMSE without the 0.1% largest terms (fireflies)."
  for s in $scenes; do
    echo
    echo "## $s"
    echo
    echo "| configuration | integrator | relMSE slope /spp | /time | MSE slope /spp | trimmed slope /spp | relMSE @ spp | trimmed | RMSE | ms/spp | t(1%) s | ratio | t(0.1%) s | ratio |"
    echo "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
    awk -F, -v s="$s" 'function h(x) { return x == "interpolated" ? "i" : x == "extrapolated" ? "e" : x == "first" ? "≤" : "" }
      NR > 1 && $1 == s {
        printf "| %s | %s | %.2f | %.2f | %.2f | %.2f | %.3g @ %s | %.3g | %.3g | %.3g | %s%s | %s | %s%s | %s |\n", $2, $3, $4, $5, $15, $17, $8, $6, $18, $16, 1000 * $19,
               ($9 == "nan" ? "—" : sprintf("%.3g", $9)), ($9 == "nan" ? "" : " " h($10)), ($13 == "nan" ? "—" : sprintf("%.2f", $13)),
               ($11 == "nan" ? "—" : sprintf("%.3g", $11)), ($11 == "nan" ? "" : " " h($12)), ($14 == "nan" ? "—" : sprintf("%.2f", $14))
      }' "$SUM"
  done
} > "$OUT/accuracy.md"
cat "$OUT/accuracy.md"
echo "bench: wrote $OUT/accuracy.csv, accuracy_summary.csv, accuracy.md and accuracy-*.png/svg" >&2
