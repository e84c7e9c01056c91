// ---------------------------------------------------------------------
// Helpers shared by the PeriDEAL benchmarks: process memory, thread CPU
// time and the chunked timing loop.
// ---------------------------------------------------------------------
#ifndef perideal_contrib_benchmark_utilities_h
#define perideal_contrib_benchmark_utilities_h

#include <deal.II/base/mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <ctime>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace PeriDEALBenchmarks
{
  /** VmRSS and VmHWM of this process in bytes. */
  inline std::pair<double, double>
  rss_bytes()
  {
    std::ifstream in("/proc/self/status");
    std::string   line;
    double        rss = 0., hwm = 0.;
    while (std::getline(in, line))
      {
        std::istringstream s(line);
        std::string        key;
        double             kb;
        s >> key >> kb;
        if (key == "VmRSS:")
          rss = kb * 1024.;
        else if (key == "VmHWM:")
          hwm = kb * 1024.;
      }
    return {rss, hwm};
  }

  inline double
  thread_cpu_seconds()
  {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
  }

  struct Timing
  {
    double wall  = 0.; ///< steps x fastest chunk's wall seconds per call (max over ranks)
    double cpu   = 0.; ///< the same with thread CPU time (sum over ranks)
    double total     = 0.; ///< wall seconds of all calls (max over ranks)
    double total_cpu = 0.; ///< thread CPU seconds of all calls (sum over ranks)
  };

  /**
   * Seconds of @p steps calls of @p f, timed in up to ten chunks: wall and
   * cpu are steps x the fastest chunk's time per call (the machine is
   * shared, the best chunk is the least disturbed one); total is the whole
   * loop (total, total_cpu). Wall time with MPI_Wtime (max over ranks) and, as a cross-check
   * that does not count time the scheduler gave to other processes, thread
   * CPU time (sum over ranks).
   */
  template <typename F>
  Timing
  time_loop(const MPI_Comm comm, const unsigned int steps, F &&f)
  {
    using dealii::Utilities::MPI::max;
    using dealii::Utilities::MPI::sum;
    const unsigned int chunks = std::min(10u, steps);
    Timing             best{std::numeric_limits<double>::max(),
                std::numeric_limits<double>::max(), 0., 0.};
    unsigned int       done = 0;
    for (unsigned int c = 0; c < chunks; ++c)
      {
        const unsigned int n = (steps - done) / (chunks - c);
        MPI_Barrier(comm);
        const double t0 = MPI_Wtime(), c0 = thread_cpu_seconds();
        for (unsigned int s = 0; s < n; ++s)
          f();
        const double cpu = sum(thread_cpu_seconds() - c0, comm);
        const double t   = max(MPI_Wtime() - t0, comm);
        best.wall        = std::min(best.wall, t / n);
        best.cpu         = std::min(best.cpu, cpu / n);
        best.total += t;
        best.total_cpu += cpu;
        done += n;
      }
    return {best.wall * steps, best.cpu * steps, best.total, best.total_cpu};
  }

  /**
   * Command line shared by the case-based benchmarks: `--case NAME` (a
   * preset), `--dim D --m M --nodes N` (one custom case named "Dd_mM"),
   * `--steps`, `--seconds`, `--help`. @p extra handles the benchmark's own
   * flags and returns false for an unknown one.
   */
  template <typename Options, typename Preset, typename Extra>
  void
  parse_case_options(int argc, char **argv, const char *program, Options &opt, Preset preset, Extra extra)
  {
    typename decltype(opt.cases)::value_type custom;
    bool                                     have_custom = false;
    for (int a = 1; a < argc; ++a)
      {
        const std::string                 arg  = argv[a];
        const std::function<std::string()> next = [&]() -> std::string {
          if (a + 1 >= argc)
            throw std::runtime_error("missing value after " + arg);
          return argv[++a];
        };
        if (arg == "--case")
          opt.cases.push_back(preset(next()));
        else if (arg == "--dim")
          custom.dim = std::stoi(next()), have_custom = true;
        else if (arg == "--m")
          custom.m = std::stoi(next()), have_custom = true;
        else if (arg == "--nodes")
          custom.nodes = std::stod(next()), have_custom = true;
        else if (arg == "--steps")
          opt.steps = std::stoi(next());
        else if (arg == "--seconds")
          opt.seconds = std::stod(next());
        else if (arg == "--help" || arg == "-h")
          {
            std::printf("see the header of contrib/benchmarks/%s.cc\n", program);
            std::exit(0);
          }
        else if (!extra(arg, next))
          throw std::runtime_error("unknown argument " + arg);
      }
    if (have_custom)
      {
        if (custom.dim < 2 || custom.dim > 3)
          throw std::runtime_error("--dim must be 2 or 3");
        custom.name = std::to_string(custom.dim) + "d_m" + std::to_string(custom.m);
        opt.cases.push_back(custom);
      }
  }
} // namespace PeriDEALBenchmarks

#endif
