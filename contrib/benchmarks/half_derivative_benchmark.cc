// Cost per step of the half-derivative history of the FEM diffusion ABC
// (EbfParameters::imposed = "half derivative"): Abc::HalfDerivativeHistory
// with the exact Gruenwald-Letnikov sum (O(n) per step and boundary DoF)
// vs the sum of exponentials (O(1)), on 386 boundary DoFs (the 3D ball of
// fem_mpi.diffusion_3d_cube_ball). One run per method appends levels up to
// the largest n; the thread CPU time of each of the 21 steps n .. n + 20 is
// measured and the median printed, for n = 1e2, 1e3, 1e4 (SOE also 1e5;
// --long: exact also 3e4, SOE also 1e6). The two methods run interleaved in
// --rounds rounds (default 3); the keys are the medians over the rounds:
//   half_derivative_step_us_<exact|soe>_n<n>: <microseconds per step>
// Then the whole disk run of fem_mpi.disk_diffusion (2D, R = 3, 6000 steps
// of dt = 5e-4, 256 boundary DoFs) with either history, CPU seconds:
//   half_derivative_disk_run_s_<exact|soe>: <seconds>
// Usage: half_derivative_benchmark [--rounds R] [--long]

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>

#include <deal.II/grid/grid_generator.h>

#include <perideal/abc/half_derivative_history.h>
#include <perideal/fem/fem_diffusion.h>

#include "benchmark_utilities.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

using namespace dealii;
using namespace PeriDEAL;

namespace
{
  double
  median(std::vector<double> v)
  {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  }

  /** Median CPU microseconds of the steps n .. n + 20 for each n in @p at (ascending). */
  std::vector<double>
  step_times(const std::string &method, const std::vector<double> &at)
  {
    constexpr unsigned int n_dofs = 386;
    Abc::HalfDerivativeHistory history;
    history.reinit(n_dofs, method, 1e-10, 5, 1e6);
    std::vector<double> values(n_dofs), h;
    std::vector<double> result;
    std::size_t         n = 0;
    // A decaying, oscillating boundary signal (the cost does not depend on it).
    const auto fill = [&]() {
      for (unsigned int a = 0; a < n_dofs; ++a)
        values[a] = std::cos(0.01 * n + a) / std::sqrt(1. + 1e-3 * n);
    };
    for (const double target : at)
      {
        for (; n < std::size_t(target); ++n)
          fill(), history.append(values.data(), h);
        std::vector<double> t;
        for (unsigned int s = 0; s < 21; ++s, ++n)
          {
            fill();
            const double c0 = PeriDEALBenchmarks::thread_cpu_seconds();
            history.append(values.data(), h);
            t.push_back(1e6 * (PeriDEALBenchmarks::thread_cpu_seconds() - c0));
          }
        result.push_back(median(t));
      }
    return result;
  }

  struct Gaussian : Function<2>
  {
    double
    value(const Point<2> &p, const unsigned int = 0) const override
    {
      return std::exp(-4. * p.square());
    }
  };

  /** CPU seconds of the 6000 steps of the disk run of fem_mpi.disk_diffusion. */
  double
  disk_run(const std::string &method)
  {
    Triangulation<2> tria;
    GridGenerator::hyper_ball(tria, Point<2>(), 3.);
    tria.refine_global(5);
    Fem::FemDiffusionParameters fp;
    fp.time_step = 5e-4;
    Abc::EbfParameters ap;
    ap.imposed                 = "half derivative";
    ap.boundary_curvature      = 1. / 3.;
    ap.half_derivative_history = method;
    Fem::FemDiffusion<2> d(tria, fp);
    d.setup(Abc::TruncationBoundary::absorbing, ap, Gaussian());
    const double c0 = PeriDEALBenchmarks::thread_cpu_seconds();
    for (unsigned int s = 0; s < 6000; ++s)
      d.advance();
    return PeriDEALBenchmarks::thread_cpu_seconds() - c0;
  }
} // namespace

int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  unsigned int                     rounds = 3;
  bool                             long_run = false;
  for (int a = 1; a < argc; ++a)
    {
      const std::string arg = argv[a];
      if (arg == "--rounds" && a + 1 < argc)
        rounds = std::atoi(argv[++a]);
      else if (arg == "--long")
        long_run = true;
      else
        {
          std::fprintf(stderr, "usage: half_derivative_benchmark [--rounds R] [--long]\n");
          return 1;
        }
    }
  std::vector<double> exact_at{1e2, 1e3, 1e4}, soe_at{1e2, 1e3, 1e4, 1e5};
  if (long_run)
    exact_at.push_back(3e4), soe_at.push_back(1e6);
  std::map<std::string, std::vector<double>> samples;
  for (unsigned int r = 0; r < rounds; ++r)
    {
      const auto e = step_times("exact", exact_at);
      const auto s = step_times("sum of exponentials", soe_at);
      for (unsigned int i = 0; i < e.size(); ++i)
        samples["half_derivative_step_us_exact_n" + std::to_string(long(exact_at[i]))].push_back(e[i]);
      for (unsigned int i = 0; i < s.size(); ++i)
        samples["half_derivative_step_us_soe_n" + std::to_string(long(soe_at[i]))].push_back(s[i]);
      samples["half_derivative_disk_run_s_exact"].push_back(disk_run("exact"));
      samples["half_derivative_disk_run_s_soe"].push_back(disk_run("sum of exponentials"));
    }
  Abc::HalfDerivativeHistory h;
  h.reinit(1, "sum of exponentials", 1e-10, 5, 1e6);
  std::printf("half_derivative_soe_exponentials: %u\n", h.n_exponentials());
  for (const auto &[key, v] : samples)
    std::printf("%s: %.4g\n", key.c_str(), median(v));
}
