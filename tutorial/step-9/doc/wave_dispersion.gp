# Relative error of the semi-discrete frequency against the continuum PD
# relation (4.90), 1D scalar waves: gnuplot wave_dispersion.gp (in this folder).
set terminal pngcairo size 900,600 noenhanced
set output 'wave_dispersion.png'
set logscale y
set format y '%.0e'
set xlabel 'k delta'
set ylabel '|omega_h - omega_PD| / omega_PD'
set title 'PD scalar waves (1D, p = 0, omega_0): dispersion error of the quadrature'
set key below maxrows 2
set xrange [0.4:3.1]
set grid
plot 'wave_dispersion.dat' using 1:2 with linespoints lw 2 pt 7 title 'standard, m = 6', \
     '' using 1:3 with linespoints lw 2 pt 5 title 'WLS-2, m = 6', \
     '' using 1:4 with linespoints lw 2 pt 9 title 'WLS-4, m = 6 (operator only)', \
     '' using 1:5 with linespoints lw 2 pt 11 title 'WLS-6, m = 6', \
     '' using 1:6 with linespoints lw 1 dt 2 pt 6 title 'standard, m = 3', \
     '' using 1:7 with linespoints lw 1 dt 2 pt 4 title 'WLS-2, m = 3'
