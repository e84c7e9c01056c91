# Plots of tutorial/step-11's results. Run in the output directory:
#   cd step-11-output && gnuplot ../../tutorial/step-11/doc/plot.gp
set datafile separator ','
set terminal pngcairo size 1200,450 font ',11'
set output 'history.png'
set multiplot layout 1,2
set xlabel 'time [us]'
set ylabel 'active fine nodes (Omega-)'
set key left top
plot 'time_series_uniform_fine.csv' every ::1 u ($1*1e6):3 w l lw 2 t 'uniform fine', \
     'time_series_adaptive_standard.csv' every ::1 u ($1*1e6):3 w l lw 2 t 'adaptive standard', \
     'time_series_adaptive_hybrid.csv' every ::1 u ($1*1e6):3 w l lw 2 dt 2 t 'adaptive hybrid'
set ylabel 'crack angle [deg]'
set yrange [40:90]
set key right bottom
plot 'time_series_uniform_fine.csv' every ::1 u ($1*1e6):($4 > 0 ? $4 : 1/0) w lp pt 7 ps 0.5 t 'uniform fine', \
     'time_series_adaptive_standard.csv' every ::1 u ($1*1e6):($4 > 0 ? $4 : 1/0) w lp pt 5 ps 0.5 t 'adaptive standard', \
     'time_series_adaptive_hybrid.csv' every ::1 u ($1*1e6):($4 > 0 ? $4 : 1/0) w lp pt 9 ps 0.5 t 'adaptive hybrid', \
     68 w l lc rgb 'gray' dt 3 t 'experiment 68'
unset multiplot
set datafile separator whitespace
set terminal pngcairo size 1200,1250 font ',11'
set output 'damage.png'
set multiplot layout 1,2
unset yrange
set size ratio -1
set xrange [0:100]
set yrange [-100:100]
set xlabel 'x [mm]'
set ylabel 'y [mm]'
set cbrange [0:0.6]
set palette defined (0 '#f0f0f0', 0.2 '#9ecae1', 0.35 '#3182bd', 0.6 '#08306b')
unset key
set title 'uniform fine: damage'
plot 'nodes_uniform_fine.dat' u 1:2:4 w p pt 5 ps 0.15 lc palette
set title 'adaptive hybrid: damage (fine), coarse nodes in orange'
plot 'nodes_adaptive_hybrid.dat' u 1:($3 == 1 ? $2 : 1/0):4 w p pt 5 ps 0.15 lc palette, \
     'nodes_adaptive_hybrid.dat' u 1:($3 == 0 ? $2 : 1/0) w p pt 5 ps 0.3 lc rgb '#fdae6b'
unset multiplot
