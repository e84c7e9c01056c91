set terminal pngcairo size 900,600 font ',11'
set output 'ball-3d.png'
set logscale xy
set xlabel 'dx (delta = 3 dx)'
set ylabel 'max |u_{PD} - u|'
set title '3D unit ball, u = x^2 - y^2 + xz + 0.3z, Dirichlet: FNM errors'
set grid
set key bottom right
plot 'ball-3d.dat' u 1:2 w lp lw 2 pt 7 t 'naive', '' u 1:3 w lp lw 2 pt 5 t 'Taylor', '' u 1:4 w lp lw 2 pt 9 t 'mirror', 0.5*x w l dt 2 t 'first order'
