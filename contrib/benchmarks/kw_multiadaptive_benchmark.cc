// ---------------------------------------------------------------------
// The multi-adaptive Kalthoff-Winkler benchmark (paper 001, Table 1):
// uniform fine, adaptive standard and adaptive hybrid at the same
// resolution in one run (serial), with the active nodes of Omega+ (coarse)
// and Omega- (fine) at the begin and the end, run times and speed-ups.
//
//   kw_multiadaptive_benchmark [--coarse-dx 1] [--fine-dx 0.5] [--delta 4]
//                              [--end-time 87.5e-6]
//
// Prints `key: value` lines (kw_<model>_..., kw_speedup_<model>_over_uniform_fine
// in CPU time, kw_wall_speedup_... in wall time) and a markdown table. The sources: 1.86x (12 cores) and 1.19x (48 cores)
// for the hybrid at dx+ = 2 dx- = 0.333 mm, delta = 4 mm (m+ = 12).
// ---------------------------------------------------------------------

#include <perideal/multigrid/multigrid_mechanics.h>

#include "benchmark_utilities.h"

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

using namespace PeriDEAL;
using namespace PeriDEAL::MultiGrid;

int
main(int argc, char **argv)
{
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  KalthoffWinkler                          kw;
  kw.coarse_dx = 1.;
  kw.fine_dx   = 0.5;
  kw.delta     = 4.;
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
      else
        {
          std::fprintf(stderr, "unknown option %s\n", key.c_str());
          return 2;
        }
    }
  std::printf("kw_coarse_dx: %g\nkw_fine_dx: %g\nkw_delta: %g\n", kw.coarse_dx, kw.fine_dx,
              kw.delta);
  struct Row
  {
    KalthoffWinkler::Result r;
    double                  cpu = 0.;
  };
  std::map<MechanicsModel, Row> rows;
  try
    {
      for (const auto model : {MechanicsModel::uniform_fine, MechanicsModel::adaptive_standard,
                               MechanicsModel::adaptive_hybrid})
        {
          kw.model        = model;
          const double c0 = PeriDEALBenchmarks::thread_cpu_seconds();
          Row          row;
          row.r   = kw.run();
          row.cpu = PeriDEALBenchmarks::thread_cpu_seconds() - c0;
          std::string name = to_string(model);
          for (auto &ch : name)
            ch = ch == ' ' ? '_' : ch;
          const auto &r = row.r;
          std::printf("kw_%s_steps: %u\n", name.c_str(), r.steps);
          std::printf("kw_%s_omega_plus_begin: %u\nkw_%s_omega_minus_begin: %u\n", name.c_str(),
                      r.coarse_begin, name.c_str(), r.fine_begin);
          std::printf("kw_%s_omega_plus_end: %u\nkw_%s_omega_minus_end: %u\n", name.c_str(),
                      r.coarse_end, name.c_str(), r.fine_end);
          std::printf("kw_%s_switching_events: %u\n", name.c_str(), r.switches);
          std::printf("kw_%s_loop_seconds: %.6g\n", name.c_str(), r.seconds);
          std::printf("kw_%s_cpu_seconds: %.6g\n", name.c_str(), row.cpu);
          std::printf("kw_%s_force_seconds: %.6g\nkw_%s_interpolation_seconds: %.6g\n"
                      "kw_%s_switching_test_seconds: %.6g\nkw_%s_switching_seconds: %.6g\n",
                      name.c_str(), r.timing[0], name.c_str(), r.timing[1], name.c_str(),
                      r.timing[2], name.c_str(), r.timing[3]);
          std::printf("kw_%s_crack_angle: %.6g\nkw_%s_crack_length: %.6g\n", name.c_str(), r.angle,
                      name.c_str(), r.length);
          std::fflush(stdout);
          rows[model] = row;
        }
    }
  catch (const std::exception &e)
    {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 1;
    }
  const auto &fine = rows[MechanicsModel::uniform_fine];
  for (const auto model : {MechanicsModel::adaptive_standard, MechanicsModel::adaptive_hybrid})
    {
      std::string name = to_string(model);
      for (auto &ch : name)
        ch = ch == ' ' ? '_' : ch;
      // The speed-up in CPU time of the run (setup included): on a shared
      // machine the wall time depends on the other processes' load, the
      // thread's CPU time does not (serial run: equal on an idle machine).
      std::printf("kw_speedup_%s_over_uniform_fine: %.4g\n", name.c_str(),
                  fine.cpu / rows[model].cpu);
      std::printf("kw_wall_speedup_%s_over_uniform_fine: %.4g\n", name.c_str(),
                  fine.r.seconds / rows[model].r.seconds);
    }
  std::printf("\n| | uniform fine | adaptive standard | adaptive hybrid |\n|---|---|---|---|\n");
  const auto line = [&](const char *what, const auto &f) {
    std::printf("| %s |", what);
    for (const auto m : {MechanicsModel::uniform_fine, MechanicsModel::adaptive_standard,
                         MechanicsModel::adaptive_hybrid})
      std::printf(" %s |", f(rows[m]).c_str());
    std::printf("\n");
  };
  line("Omega+ / Omega- active, t = 0", [](const Row &r) {
    return std::to_string(r.r.coarse_begin) + " / " + std::to_string(r.r.fine_begin);
  });
  line("Omega+ / Omega- active, t = T", [](const Row &r) {
    return std::to_string(r.r.coarse_end) + " / " + std::to_string(r.r.fine_end);
  });
  line("time loop, wall [s]", [](const Row &r) { return std::to_string(r.r.seconds); });
  line("run, CPU [s]", [](const Row &r) { return std::to_string(r.cpu); });
  line("speed-up (CPU)", [&](const Row &r) { return std::to_string(fine.cpu / r.cpu); });
  line("crack angle [deg]", [](const Row &r) { return std::to_string(r.r.angle); });
  return 0;
}
