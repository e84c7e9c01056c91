// Overhead of the EBF absorbing boundary of the deal.II FEM wave near field
// (Fem::FemWave, Q1 lumped mass, velocity Verlet) as a fraction of the whole
// explicit step, on the E13 near field of the dissertation (Sect. 4.2.5):
// (-26, 26)^2, h = 0.5 (11,025 DoFs, 416 absorbing), chi = 1, d = 0.0125,
// dt = 5e-4. Prints `abc_overhead_fraction_fem_wave_2d: <x>` (the key
// abc_overhead_fraction_fem_2d of abc_benchmark is the FEM diffusion ABC).
// Usage: fem_abc_benchmark [steps] (default 2000).

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>

#include <deal.II/grid/grid_generator.h>

#include <perideal/fem/fem_wave.h>

#include <cmath>
#include <cstdlib>
#include <iostream>

using namespace dealii;
using namespace PeriDEAL;

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  const unsigned int               steps = argc > 1 ? std::atoi(argv[1]) : 2000;
  Triangulation<2>                 tria;
  GridGenerator::subdivided_hyper_cube(tria, 104, -26., 26.);
  Fem::FemWaveParameters fp;
  fp.damping   = 0.0125;
  fp.time_step = 5e-4;
  Abc::WaveAbcParameters abc;
  abc.wave_number_range = 1.;
  abc.direction_range   = M_PI / 8.;
  abc.cone_angle        = 0.5;
  const ScalarFunctionFromFunctionObject<2> u0(
    [](const Point<2> &p) { return std::exp(-std::log(2.) * p.square() / 9.); });
  Fem::FemWave<2> wave(tria, fp, Fem::WaveBoundary::absorbing, abc, u0);
  for (unsigned int s = 0; s < steps; ++s)
    wave.advance();
  std::cout << "abc_overhead_fraction_fem_wave_2d: " << wave.abc_seconds / wave.step_seconds << std::endl;
}
