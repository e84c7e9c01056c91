// Overhead of the EBF absorbing boundary (one dot product per absorbing
// node and step) as a fraction of the whole explicit step. Prints
// `key: value` lines:
//   abc_overhead_fraction_pd_2d: PD scalar waves (E14 parameters: p = 2,
//     dx = 0.25, delta = 6 dx, Delta k = 1, 11 x 11 modes) on the source's
//     disc R = 26 (33,949 nodes as in Sect. 4.2.6); issue 4's target is < 0.05.
//     abc_seconds / step_seconds of advance() (wall; median over blocks of
//     10 steps). _vs_no_abc: the whole cost, (T_abc - T_none) / T_abc in CPU
//     time against the same run stepping without any ABC work (interleaved
//     blocks, median; see pd_wave_fraction). Mostly negative since
//     session 12: the run with the ABC does not compute the PD sums of the
//     overwritten layer rows, which the free truncation does;
//   abc_overhead_fraction_pd_diffusion_{1d,2d}, abc_overhead_fraction_fem_{1d,2d}:
//     diffusion (the PD keys were abc_overhead_fraction_pd_{1d,2d} before).
// Sizes: 2D PD box (-4,4)^2, dx = 1/16, delta = 4 dx (16,641 nodes,
// 1,984 absorbing); 2D FEM Q1 lumped on (-4,4)^2 with 256^2 cells;
// 1D: (-30,30) at dx = 0.125 as in step-5. Usage: abc_benchmark [steps]
// [--wave-only] [--no-share] (--wave-only: only the PD wave keys; --no-share:
// one set of updating vectors per absorbing node instead of per class of
// congruent clouds, for A/B runs).

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>

#include <deal.II/grid/grid_generator.h>

#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/abc/wave_abc_layers.h>
#include <perideal/abc/pd_unbounded_diffusion.h>
#include <perideal/fem/fem_diffusion.h>


#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <string>
#include <vector>

using namespace dealii;
using namespace PeriDEAL;

template <int dim>
class Gaussian : public Function<dim>
{
public:
  double
  value(const Point<dim> &p, const unsigned int = 0) const override
  {
    return std::exp(-4. * p.square());
  }
};

template <int dim>
double
pd_fraction(const double L, const double dx, const unsigned int steps)
{
  Point<dim> lo, hi;
  for (unsigned int d = 0; d < dim; ++d)
    lo[d] = -L, hi[d] = L;
  BoxDomain<dim>    box(lo, hi);
  LatticeParameters lp;
  lp.dx    = dx;
  lp.delta = 4. * dx;
  DiffusionModelParameters model;
  model.exponent = 1.;
  Abc::EbfParameters ap;
  ap.cloud_radius = 0.5 * lp.delta * (1. + 1e-9);
  Abc::PdUnboundedDiffusion<dim> run(MPI_COMM_WORLD);
  const double dt = 0.5 * dx * dx / (2. * dim);
  run.setup(box, lp, model, dt, Abc::TruncationBoundary::absorbing, ap, Gaussian<dim>());
  for (unsigned int n = 0; n < steps; ++n)
    run.advance();
  return Utilities::MPI::sum(run.abc_seconds, MPI_COMM_WORLD) /
         Utilities::MPI::sum(run.step_seconds, MPI_COMM_WORLD);
}

// CPU seconds of this thread (the machine is shared: wall time is noisy).
double
cpu_seconds()
{
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

double
median(std::vector<double> x)
{
  std::sort(x.begin(), x.end());
  const std::size_t n = x.size();
  return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

struct WaveOverhead
{
  double fraction = 0., fraction_vs_no_abc = 0., step_seconds = 0., step_seconds_no_abc = 0.;
  /** The timers' ratio of sums over the same steps (the key's definition before session 12). */
  double fraction_of_sums = 0.;
  /** Coefficient sets stored (classes of congruent clouds) and absorbing nodes. */
  types::global_dof_index n_classes = 0, n_clouds = 0;
  /** Largest relative change of the updating vectors by the sharing. */
  double shared_difference = 0.;
};

// fraction: the timers of advance(), abc_seconds / step_seconds (wall), over
// the first steps / 4 steps (the definition of sessions <= 9), since
// session 12 the median of the ratios of blocks of 10 steps (a block in
// which the process was preempted on the shared machine no longer moves
// the key; fraction_of_sums: the ratio of the sums). They time the
// update itself but not what it costs the rest of the step (its 1.6 MB of
// coefficients and cloud values evict operator data), so fraction_vs_no_abc
// also measures the step against the same near field without any ABC work,
// on the same objects and memory (a separate free-truncation run differs by
// +-10 % in step time from its allocation alone on this VM): the run then
// steps in turn in blocks of 10 timed steps (CPU seconds) with the ABC and
// without it (set_abc_skipped(true): the free truncation), alternating the
// order, each block after one untimed step in its mode. Per round,
// (T_abc - T_none) / T_abc; the key is the median over the rounds.
WaveOverhead
pd_wave_fraction(const double R, const unsigned int steps, const Abc::WaveAbcParameters &ap)
{
  LatticeParameters lp;
  lp.dx    = 0.25;
  lp.delta = 6. * lp.dx;
  ScalarWaveParameters mp;
  mp.exponent  = 2.;
  mp.damping   = 0.0125;
  mp.time_step = 0.02;
  Abc::PdUnboundedWave<2> run(MPI_COMM_WORLD);
  run.setup(BallDomain<2>(Point<2>(), R), lp, mp, Abc::WaveTruncation::absorbing, ap, Gaussian<2>());
  WaveOverhead o;
  o.n_classes = run.absorbing_boundary().statistics().n_classes;
  o.n_clouds  = run.absorbing_boundary().statistics().n_absorbing;
  o.shared_difference = run.absorbing_boundary().statistics().max_shared_difference;
  const unsigned int  block = 10;
  std::vector<double> timer_fractions;
  for (unsigned int b = 0; b < std::max(1u, steps / 4 / block); ++b)
    {
      const double abc0 = run.abc_seconds, step0 = run.step_seconds;
      for (unsigned int n = 0; n < block; ++n)
        run.advance();
      timer_fractions.push_back(Utilities::MPI::sum(run.abc_seconds - abc0, MPI_COMM_WORLD) /
                                Utilities::MPI::sum(run.step_seconds - step0, MPI_COMM_WORLD));
    }
  o.fraction         = median(timer_fractions);
  o.fraction_of_sums = Utilities::MPI::sum(run.abc_seconds, MPI_COMM_WORLD) /
                       Utilities::MPI::sum(run.step_seconds, MPI_COMM_WORLD);
  const unsigned int  n_rounds = std::max(1u, steps / 2 / block);
  std::vector<double> f, t[2];
  for (unsigned int b = 0; b < n_rounds; ++b)
    {
      double seconds[2];
      for (unsigned int q = 0; q < 2; ++q)
        {
          const unsigned int k = (b + q) % 2; // 0 with the ABC, 1 without
          run.set_abc_skipped(k == 1);
          run.advance();
          const double start = cpu_seconds();
          for (unsigned int n = 0; n < block; ++n)
            run.advance();
          seconds[k] = Utilities::MPI::sum(cpu_seconds() - start, MPI_COMM_WORLD) / block;
          t[k].push_back(seconds[k]);
        }
      f.push_back((seconds[0] - seconds[1]) / seconds[0]);
    }
  o.fraction_vs_no_abc  = median(f);
  o.step_seconds        = median(t[0]);
  o.step_seconds_no_abc = median(t[1]);
  return o;
}

template <int dim>
double
fem_fraction(const double L, const unsigned int cells, const unsigned int steps)
{
  Triangulation<dim> tria;
  GridGenerator::subdivided_hyper_cube(tria, cells, -L, L);
  const double                dx = 2. * L / cells;
  Fem::FemDiffusionParameters fp;
  fp.time_step = 0.5 * dx * dx / (2. * dim);
  Abc::EbfParameters ap;
  ap.cloud_radius = 2. * dx * (1. + 1e-9);
  Fem::FemDiffusion<dim> run(tria, fp);
  run.setup(Abc::TruncationBoundary::absorbing, ap, Gaussian<dim>());
  for (unsigned int n = 0; n < steps; ++n)
    run.advance();
  return run.abc_seconds / run.step_seconds;
}

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  unsigned int steps = 2000;
  bool         wave_only = false, share = true;
  for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      if (arg == "--wave-only")
        wave_only = true;
      else if (arg == "--no-share")
        share = false;
      else
        steps = std::atoi(argv[i]);
    }
  const double R = 26.;
  Abc::WaveAbcParameters plane;
  plane.cone_angle             = 0.5;
  plane.share_updating_vectors = share;
  // The long-run monotone layer adopted for E14 in session 15: clouds of
  // 4 dx, 16-20 points per dot product instead of 5-8.
  Abc::WaveAbcParameters monotone = Abc::WaveAbcLayers::curved_monotone(0.25, R);
  monotone.share_updating_vectors = share;
  for (const auto &[suffix, ap] : {std::pair{std::string(""), plane}, std::pair{std::string("_monotone"), monotone}})
    {
      const WaveOverhead wave2 = pd_wave_fraction(R, steps, ap);
      if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
        std::cout << "abc_overhead_fraction_pd_2d" << suffix << ": " << wave2.fraction << "\n"
                  << "abc_overhead_fraction_pd_2d" << suffix << "_vs_no_abc: " << wave2.fraction_vs_no_abc << "\n"
                  << "abc_timer_fraction_of_sums_pd_2d" << suffix << ": " << wave2.fraction_of_sums << "\n"
                  << "abc_step_cpu_seconds_pd_2d" << suffix << ": " << wave2.step_seconds << "\n"
                  << "no_abc_step_cpu_seconds_pd_2d" << suffix << ": " << wave2.step_seconds_no_abc << "\n"
                  << "abc_updating_vector_sets_pd_2d" << suffix << ": " << wave2.n_classes << "\n"
                  << "abc_clouds_pd_2d" << suffix << ": " << wave2.n_clouds << "\n"
                  << "abc_shared_updating_vector_difference_pd_2d" << suffix << ": " << wave2.shared_difference
                  << std::endl;
    }
  if (wave_only)
    return 0;
  const double pd2 = pd_fraction<2>(4., 1. / 16., steps);
  const double pd1 = pd_fraction<1>(30., 0.125, 20 * steps);
  if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
    {
      const double fem2 = fem_fraction<2>(4., 256, steps);
      const double fem1 = fem_fraction<1>(30., 480, 20 * steps);
      std::cout << "abc_overhead_fraction_pd_diffusion_2d: " << pd2 << "\n"
                << "abc_overhead_fraction_pd_diffusion_1d: " << pd1 << "\n"
                << "abc_overhead_fraction_fem_2d: " << fem2 << "\n"
                << "abc_overhead_fraction_fem_1d: " << fem1 << std::endl;
    }
  return 0;
}
