// ---------------------------------------------------------------------
// The multi-adaptive Kalthoff-Winkler benchmark (paper 001, Table 1):
// the library's fastest uniform-fine standard scheme (PeriDEAL::
// MechanicsSolver with the bond-based PMB model, i.e. the AVX-512 lattice
// sweep of BondBasedOperator) against the two-grid MultiGrid::
// MechanicsSolver, adaptive standard and adaptive hybrid, at the same fine
// lattice, horizon, material, time step and end time (serial), with the
// active nodes of Omega+ (coarse) and Omega- (fine) at the begin and the
// end, run times, speed-ups, crack angles and the damage maps compared.
//
//   kw_multiadaptive_benchmark [--coarse-dx 1] [--fine-dx 0.5] [--delta 4]
//                              [--end-time 87.5e-6] [--rounds 3]
//                              [--directory <tmp>/perideal-kw-multiadaptive]
//                              [--damage-file <file>]
//
// The runs are interleaved (uniform fine by the library, uniform fine by
// the two-grid solver, adaptive standard, adaptive hybrid, repeated
// --rounds times) and each figure is the median over the
// rounds of the thread CPU time of set-up + time loop: on a shared machine
// the CPU time does not depend on the other processes' load as the wall
// time does. Prints `key: value` lines (kw_<model>_...,
// kw_speedup_<model>_over_uniform_fine) and a markdown table. The sources:
// 1.86x (12 cores) and 1.19x (48 cores) for the hybrid at
// dx+ = 2 dx- = 0.333 mm, delta = 4 mm (m+ = 12).
// ---------------------------------------------------------------------

#include <perideal/multigrid/multigrid_mechanics.h>
#include <perideal/time_stepping/mechanics_solver.h>

#include "../../tests/hybrid_kw/kalthoff_winkler_case.h"
#include "benchmark_utilities.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

using namespace PeriDEAL;
using MultiGrid::KalthoffWinkler;
using MGModel = MultiGrid::MechanicsModel;

namespace
{
  struct Run
  {
    double       cpu = 0., wall = 0., angle = 0., length = 0.;
    unsigned int steps = 0, coarse_begin = 0, fine_begin = 0, coarse_end = 0, fine_end = 0,
                 switches = 0;
    std::array<double, 4> timing{{0., 0., 0., 0.}};
    /** Damage per fine lattice node (x fastest), 0 where not active. */
    std::vector<double> damage;
  };

  double
  median(std::vector<double> x)
  {
    std::sort(x.begin(), x.end());
    return x.size() % 2 ? x[x.size() / 2] : 0.5 * (x[x.size() / 2 - 1] + x[x.size() / 2]);
  }

  // The library's standard scheme on the fine lattice (the same plate,
  // pre-cracks, material and impact as KalthoffWinkler: the case of
  // tests/hybrid_kw), with time step dt.
  Run
  run_library(const KalthoffWinkler &kw, const double dt, const std::string &dir)
  {
    Run          r;
    const double c0 = PeriDEALBenchmarks::thread_cpu_seconds();
    const auto   w0 = std::chrono::steady_clock::now();
    auto p = kalthoff_winkler(kw.fine_dx, kw.delta, kw.end_time, "standard", 0.95, dir, 100000000);
    p.time_step = dt;
    MechanicsSolver<2> s(MPI_COMM_WORLD, p);
    s.setup();
    s.run();
    r.cpu  = PeriDEALBenchmarks::thread_cpu_seconds() - c0;
    r.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    const auto m = s.measure();
    // measure() gives the angle in [0, 180); the multi-grid solver in (-90, 90].
    r.angle  = m.crack_angle > 90. ? m.crack_angle - 180. : m.crack_angle;
    r.length = m.crack_length;
    r.steps  = s.integrator().step();
    r.fine_begin = r.fine_end = s.discretization().n_global();
    PeriDEAL::Vector phi;
    s.discretization().initialize_vector(phi);
    s.model().damage(phi);
    const unsigned int nx = std::lround(100. / kw.fine_dx), ny = std::lround(200. / kw.fine_dx);
    r.damage.assign(nx * ny, 0.);
    const auto &x = s.discretization().position;
    for (unsigned int i = 0; i < s.discretization().n_owned(); ++i)
      {
        const auto ix = std::lround(x[i][0] / kw.fine_dx - 0.5),
                   iy = std::lround((x[i][1] + 100.) / kw.fine_dx - 0.5);
        r.damage[iy * nx + ix] = phi.local_element(i);
      }
    return r;
  }

  Run
  run_multigrid(KalthoffWinkler kw, const MGModel model)
  {
    using Solver = MultiGrid::MechanicsSolver<2>;
    kw.model = model;
    Run          r;
    const double c0 = PeriDEALBenchmarks::thread_cpu_seconds();
    const auto   w0 = std::chrono::steady_clock::now();
    const auto   res = kw.run([&r](const Solver &s) {
      if (s.step() == 0)
        return;
      r.damage.assign(s.n_nodes(Solver::fine), 0.);
      for (unsigned int i = 0; i < s.n_nodes(Solver::fine); ++i)
        if (s.is_active(Solver::fine, i))
          r.damage[i] = s.damage(Solver::fine, i);
    });
    r.cpu          = PeriDEALBenchmarks::thread_cpu_seconds() - c0;
    r.wall         = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    r.angle        = res.angle;
    r.length       = res.length;
    r.steps        = res.steps;
    r.coarse_begin = res.coarse_begin;
    r.fine_begin   = res.fine_begin;
    r.coarse_end   = res.coarse_end;
    r.fine_end     = res.fine_end;
    r.switches     = res.switches;
    r.timing       = res.timing;
    return r;
  }
} // namespace

int
main(int argc, char **argv)
{
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  KalthoffWinkler                          kw;
  kw.coarse_dx        = 1.;
  kw.fine_dx          = 0.5;
  kw.delta            = 4.;
  unsigned int rounds = 3;
  std::string  damage_file;
  std::string  dir =
    (std::filesystem::temp_directory_path() / "perideal-kw-multiadaptive").string();
  for (int i = 1; i + 1 < argc; i += 2)
    {
      const std::string key = argv[i];
      const double      val = std::atof(argv[i + 1]);
      if (key == "--coarse-dx")
        kw.coarse_dx = val;
      else if (key == "--fine-dx")
        kw.fine_dx = val;
      else if (key == "--delta")
        kw.delta = val;
      else if (key == "--end-time")
        kw.end_time = val;
      else if (key == "--rounds" && val >= 1.)
        rounds = static_cast<unsigned int>(val);
      else if (key == "--directory")
        dir = argv[i + 1];
      else if (key == "--damage-file")
        damage_file = argv[i + 1];
      else
        {
          std::fprintf(stderr, "unknown option %s %s\n", key.c_str(), argv[i + 1]);
          return 2;
        }
    }
  std::printf("kw_coarse_dx: %g\nkw_fine_dx: %g\nkw_delta: %g\nkw_rounds: %u\n", kw.coarse_dx,
              kw.fine_dx, kw.delta, rounds);
  // uniform_fine: the library's standard scheme (the reference of the
  // speed-up keys); multigrid_uniform_fine: the two-grid solver's own
  // uniform fine model (the same lattice sweep idea, without the library's
  // vector/Verlet layers), reported as a second reference.
  const std::vector<std::string> names{"uniform_fine", "multigrid_uniform_fine",
                                       "adaptive_standard", "adaptive_hybrid"};
  std::map<std::string, std::vector<Run>> runs;
  try
    {
      // The time step of all runs: that of the adaptive hybrid (the WLS
      // stencil's stability bound is the smallest).
      KalthoffWinkler hk = kw;
      hk.model           = MGModel::adaptive_hybrid;
      MultiGrid::MechanicsSolver<2> probe(hk.parameters());
      hk.load(probe);
      const double dt = probe.time_step();
      std::printf("kw_time_step: %.6g\n", dt);
      for (unsigned int round = 0; round < rounds; ++round)
        {
          runs["uniform_fine"].push_back(run_library(kw, dt, dir));
          runs["multigrid_uniform_fine"].push_back(run_multigrid(kw, MGModel::uniform_fine));
          runs["adaptive_standard"].push_back(run_multigrid(kw, MGModel::adaptive_standard));
          runs["adaptive_hybrid"].push_back(run_multigrid(kw, MGModel::adaptive_hybrid));
        }
    }
  catch (const std::exception &e)
    {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
  std::map<std::string, double> cpu, wall;
  for (const auto &name : names)
    {
      std::vector<double> c, w;
      for (const auto &r : runs[name])
        {
          c.push_back(r.cpu);
          w.push_back(r.wall);
        }
      cpu[name]  = median(c);
      wall[name] = median(w);
    }
  const auto &ref = runs["uniform_fine"].back();
  if (!damage_file.empty())
    {
      // x y and the damage of the uniform fine (library, two-grid solver),
      // adaptive standard and adaptive hybrid runs per fine node (gnuplot
      // blocks per row).
      std::FILE         *out = std::fopen(damage_file.c_str(), "w");
      const unsigned int nx  = std::lround(100. / kw.fine_dx);
      for (std::size_t i = 0; out && i < ref.damage.size(); ++i)
        {
          std::fprintf(out, "%g %g %.4f %.4f %.4f %.4f\n", (i % nx + 0.5) * kw.fine_dx,
                       -100. + (i / nx + 0.5) * kw.fine_dx, ref.damage[i],
                       runs["multigrid_uniform_fine"].back().damage[i],
                       runs["adaptive_standard"].back().damage[i],
                       runs["adaptive_hybrid"].back().damage[i]);
          if (i % nx == nx - 1)
            std::fprintf(out, "\n");
        }
      if (out)
        std::fclose(out);
    }
  for (const auto &name : names)
    {
      const Run  &r = runs[name].back();
      const char *n = name.c_str();
      std::printf("kw_%s_steps: %u\n", n, r.steps);
      std::printf("kw_%s_omega_plus_begin: %u\nkw_%s_omega_minus_begin: %u\n", n, r.coarse_begin,
                  n, r.fine_begin);
      std::printf("kw_%s_omega_plus_end: %u\nkw_%s_omega_minus_end: %u\n", n, r.coarse_end, n,
                  r.fine_end);
      std::printf("kw_%s_switching_events: %u\n", n, r.switches);
      std::printf("kw_%s_cpu_seconds: %.6g\nkw_%s_wall_seconds: %.6g\n", n, cpu[name], n,
                  wall[name]);
      if (name != "uniform_fine")
        {
          std::printf("kw_%s_force_seconds: %.6g\nkw_%s_interpolation_seconds: %.6g\n"
                      "kw_%s_switching_test_seconds: %.6g\nkw_%s_switching_seconds: %.6g\n",
                      n, r.timing[0], n, r.timing[1], n, r.timing[2], n, r.timing[3]);
          std::printf("kw_%s_omega_minus_fraction_begin: %.4g\nkw_%s_omega_minus_fraction_end: %.4g\n",
                      n, double(r.fine_begin) / ref.damage.size(), n,
                      double(r.fine_end) / ref.damage.size());
          // Damage maps: fine nodes whose damage differs from the uniform
          // fine run's by more than 0.2, against that run's damaged nodes.
          unsigned int differ = 0, damaged = 0;
          double       max_diff = 0.;
          for (std::size_t i = 0; i < ref.damage.size(); ++i)
            {
              damaged += ref.damage[i] > 0.2;
              differ += std::abs(r.damage[i] - ref.damage[i]) > 0.2;
              max_diff = std::max(max_diff, std::abs(r.damage[i] - ref.damage[i]));
            }
          std::printf("kw_%s_damage_differs_nodes: %u\nkw_%s_damaged_nodes_uniform_fine: %u\n"
                      "kw_%s_max_damage_difference: %.3g\n",
                      n, differ, n, damaged, n, max_diff);
        }
      std::printf("kw_%s_crack_angle: %.6g\nkw_%s_crack_length: %.6g\n", n, r.angle, n, r.length);
    }
  for (const auto &name : {std::string("adaptive_standard"), std::string("adaptive_hybrid")})
    {
      std::printf("kw_speedup_%s_over_uniform_fine: %.4g\n", name.c_str(),
                  cpu["uniform_fine"] / cpu[name]);
      std::printf("kw_wall_speedup_%s_over_uniform_fine: %.4g\n", name.c_str(),
                  wall["uniform_fine"] / wall[name]);
      std::printf("kw_speedup_%s_over_multigrid_uniform_fine: %.4g\n", name.c_str(),
                  cpu["multigrid_uniform_fine"] / cpu[name]);
    }
  std::printf("\n| | uniform fine (library sweep) | uniform fine (two-grid solver) | adaptive "
              "standard | adaptive hybrid |\n|---|---|---|---|---|\n");
  const auto line = [&](const char *what, const auto &f) {
    std::printf("| %s |", what);
    for (const auto &name : names)
      std::printf(" %s |", f(name, runs[name].back()).c_str());
    std::printf("\n");
  };
  line("Omega+ / Omega- active, t = 0", [](const std::string &, const Run &r) {
    return std::to_string(r.coarse_begin) + " / " + std::to_string(r.fine_begin);
  });
  line("Omega+ / Omega- active, t = T", [](const std::string &, const Run &r) {
    return std::to_string(r.coarse_end) + " / " + std::to_string(r.fine_end);
  });
  line("steps", [](const std::string &, const Run &r) { return std::to_string(r.steps); });
  line("run, CPU [s] (median)", [&](const std::string &n, const Run &) {
    return std::to_string(cpu[n]);
  });
  line("speed-up (CPU)", [&](const std::string &n, const Run &) {
    return std::to_string(cpu["uniform_fine"] / cpu[n]);
  });
  line("crack angle [deg]", [](const std::string &, const Run &r) { return std::to_string(r.angle); });
  return 0;
}
