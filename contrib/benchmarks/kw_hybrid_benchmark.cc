// ---------------------------------------------------------------------
// Kalthoff-Winkler (dissertation Sect. 3.3.1, Table 3.3): the uniform
// standard scheme against the adaptive hybrid configuration (standard PMB on
// Omega_s, WLS-2 on Omega_w, switching (3.80)) at the same resolution and
// time step. Prints a table like Table 3.3 and `key: value` lines.
//
//   kw_hybrid_benchmark [--dx 0.25] [--m 8] [--end-time 87.5e-6] [--sigma 0.95]
//                       [--interval 1] [--every-step 0] [--bound lattice|budget]
//                       [--chunk 16] [--half-stencil 0|1] [--grouped-test 0|1]
//                       [--row-test 0|1] [--node-order lattice|cells]
//                       [--standard-node-order lattice|cells]
//                       [--directory kw-hybrid-benchmark]
//
// Timing: the machine may be shared, so the two runs advance in turns, in
// chunks of --chunk steps (order alternating), and each chunk is charged its
// thread CPU time; the speed-up is the ratio of the total CPU times (the
// median ratio over the chunks is printed too). The standard scheme is
// BondBasedOperator's fastest loop (the lattice sweep where available).
// --every-step 1 tests (3.80) on every bond at every step instead of the
// amortized test (the same result, see HybridBondBasedModel); --bound
// budget uses StretchBudget per length class instead of the lattice bound
// (the same result, more exact node tests). --half-stencil 1 evaluates the
// Omega_s rows as a half-stencil sweep with reactions instead of their full
// stencils (HybridMechanicsParameters::half_stencil, default off; the same
// bonds, another summation order). --grouped-test 0 keeps the per-offset
// masked kernel of the exact switching test (length_grouped_test, default
// on; the same q bit for bit); --row-test 0 the grouped kernel's per-offset
// loads instead of one load per stencil row (row_shared_test, default on;
// the same q bit for bit). --node-order cells numbers the hybrid run's nodes
// by cells (LatticeParameters::lattice_order; the default lattice numbers
// them by lattice rows, so that its per-step copy of u into the lattice box
// is one run per dimension; the same results). --standard-node-order does
// the same for the standard run (default lattice: both runs in the same
// order, so that the numbering favours neither). The keys
// kw_hybrid_state_hash_* are FNV-1a hashes of the final displacement and
// damage bits of each run, node by node in the standard run's order for
// both runs; kw_hybrid_state_hash_by_id_* the same in particle id order,
// which does not depend on either numbering (with both runs in lattice
// order the two pairs coincide; --standard-node-order cells gives the
// hashes of sessions 13-16, b41a2c30deaaae34 / 06b8976784912402).
//
// The plate is that of tutorial/step-4 (100 x 200 mm, pre-cracks of 50 mm
// at y = +-25). The source uses dx = 0.25 mm, delta = 2 mm (m = 8) and
// dt = 2e-9 s (43,500 steps); at 0.9 x the critical step the same lattice
// takes 705 steps (~1 min for both runs), so that is the default. The
// initial and final Omega_s are bands whose widths scale with delta: at
// dx = 0.5, delta = 4 (m = 8, --dx 0.5) they cover about twice the
// source's fractions (20 % -> 36.5 % against 10 % -> 15.8 % at delta = 2).
// ---------------------------------------------------------------------

#include <deal.II/base/mpi.h>

#include <perideal/time_stepping/mechanics_solver.h>

#include "../../tests/hybrid_kw/kalthoff_winkler_case.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <ctime>
#include <map>
#include <vector>
#include <iomanip>
#include <iostream>
#include <string>

using namespace dealii;
using namespace PeriDEAL;

namespace
{
  double
  cpu_seconds()
  {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
  }

  // Damage of the owned nodes (serial benchmark: all nodes).
  std::vector<double>
  damage_of(const MechanicsSolver<2> &s)
  {
    PeriDEAL::Vector phi;
    s.discretization().initialize_vector(phi);
    s.model().damage(phi);
    return std::vector<double>(phi.begin(), phi.begin() + s.discretization().n_owned());
  }

  /**
   * FNV-1a of the bits of the final displacement and damage (one rank), node
   * by node in the order @p order (local indices of @p s; the same ids in
   * the same order for both runs, whatever their numbering).
   */
  std::uint64_t
  state_hash(const MechanicsSolver<2> &s, const std::vector<double> &damage,
             const std::vector<unsigned int> &order)
  {
    std::uint64_t hash = 1469598103934665603ull;
    const auto    add  = [&](const double v) {
      const auto *bytes = reinterpret_cast<const unsigned char *>(&v);
      for (std::size_t k = 0; k < sizeof(double); ++k)
        hash = (hash ^ bytes[k]) * 1099511628211ull;
    };
    for (unsigned int d = 0; d < 2; ++d)
      for (const unsigned int i : order)
        add(s.integrator().displacement[d].local_element(i));
    for (const unsigned int i : order)
      add(damage[i]);
    return hash;
  }

  /** Local index in @p s of each node of @p reference, in @p reference's order. */
  std::vector<unsigned int>
  same_nodes(const MechanicsSolver<2> &s, const MechanicsSolver<2> &reference)
  {
    std::map<types::particle_index, unsigned int> local;
    for (unsigned int i = 0; i < s.discretization().n_owned(); ++i)
      local[s.discretization().id[i]] = i;
    std::vector<unsigned int> order;
    for (unsigned int i = 0; i < reference.discretization().n_owned(); ++i)
      order.push_back(local.at(reference.discretization().id[i]));
    return order;
  }
} // namespace


int
main(int argc, char **argv)
{
  Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  double      dx = 0.25, m = 8., end_time = 87.5e-6, sigma = 0.95;
  int         interval = 1, every_step = 0, chunk = 16, half_stencil = -1, grouped_test = -1,
              row_test = -1;
  std::string dir = "kw-hybrid-benchmark", bound = "lattice", node_order = "lattice",
              standard_node_order = "lattice";
  for (int a = 1; a + 1 < argc; a += 2)
    {
      const std::string key = argv[a], value = argv[a + 1];
      if (key == "--dx")
        dx = std::stod(value);
      else if (key == "--m")
        m = std::stod(value);
      else if (key == "--end-time")
        end_time = std::stod(value);
      else if (key == "--sigma")
        sigma = std::stod(value);
      else if (key == "--interval")
        interval = std::stoi(value);
      else if (key == "--every-step")
        every_step = std::stoi(value);
      else if (key == "--bound" && (value == "lattice" || value == "budget"))
        bound = value;
      else if (key == "--half-stencil")
        half_stencil = std::stoi(value);
      else if (key == "--grouped-test")
        grouped_test = std::stoi(value);
      else if (key == "--row-test")
        row_test = std::stoi(value);
      else if (key == "--node-order" && (value == "lattice" || value == "cells"))
        node_order = value;
      else if (key == "--standard-node-order" && (value == "lattice" || value == "cells"))
        standard_node_order = value;
      else if (key == "--chunk")
        chunk = std::max(1, std::stoi(value));
      else if (key == "--directory")
        dir = value;
      else
        {
          std::cerr << "unknown option " << key << std::endl;
          return 2;
        }
    }
  AssertThrow(Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) == 1,
              ExcMessage("kw_hybrid_benchmark is serial (thread CPU times)."));
  const double delta = m * dx;

  // Hybrid first: its time step bound (WLS symbol) is the smaller one, and
  // both runs use it.
  double t0 = cpu_seconds();
  auto ph = kalthoff_winkler(dx, delta, end_time, "hybrid adaptive", sigma, dir + "/hybrid", 100000000);
  ph.hybrid.check_interval  = interval;
  ph.hybrid.switching_bound = every_step == 0;
  ph.hybrid.lattice_bound   = bound == "lattice";
  if (half_stencil >= 0)
    ph.hybrid.half_stencil = half_stencil != 0;
  if (grouped_test >= 0)
    ph.hybrid.length_grouped_test = grouped_test != 0;
  if (row_test >= 0)
    ph.hybrid.row_shared_test = row_test != 0;
  ph.lattice.lattice_order = node_order == "lattice";
  MechanicsSolver<2> hybrid(MPI_COMM_WORLD, ph);
  hybrid.setup();
  const double hybrid_setup = cpu_seconds() - t0;
  const double initial      = hybrid.hybrid_model()->standard_fraction();
  auto ps = kalthoff_winkler(dx, delta, end_time, "standard", sigma, dir + "/standard", 100000000);
  ps.time_step = hybrid.integrator().time_step();
  ps.lattice.lattice_order = standard_node_order == "lattice";
  t0           = cpu_seconds();
  MechanicsSolver<2> standard(MPI_COMM_WORLD, ps);
  standard.setup();
  const double standard_setup = cpu_seconds() - t0;
  // Initial output outside the timing.
  standard.run(0);
  hybrid.run(0);

  // Interleaved chunks up to the last step (its snapshot output is not
  // timed, for either run).
  const unsigned int n_steps = (unsigned int)std::llround(end_time / hybrid.integrator().time_step());
  double             ts = 0., th = 0.;
  std::vector<double> ratio;
  for (unsigned int round = 0; standard.integrator().step() + 1 < n_steps; ++round)
    {
      const unsigned int n = std::min<unsigned int>(chunk, n_steps - 1 - standard.integrator().step());
      double             cs = 0., ch = 0.;
      for (unsigned int k = 0; k < 2; ++k)
        {
          const bool std_turn = (k == 0) == (round % 2 == 0);
          const double start  = cpu_seconds();
          (std_turn ? standard : hybrid).run(n);
          (std_turn ? cs : ch) += cpu_seconds() - start;
        }
      ts += cs;
      th += ch;
      ratio.push_back(cs / ch);
    }
  standard.run();
  hybrid.run();
  std::sort(ratio.begin(), ratio.end());
  const double median_ratio = ratio.empty() ? 0. : ratio[ratio.size() / 2];

  const auto   ms = standard.measure(), mh = hybrid.measure();
  const auto  *hm = hybrid.hybrid_model();
  const double final_fraction = hm->standard_fraction();
  const auto   parts          = hm->seconds;
  const auto   overstretched  = hm->n_overstretched_bonds();

  // Damage maps: largest difference, and the cracked nodes (damage >= 0.35)
  // of one run farther than 2 dx from every cracked node of the other (the
  // criterion of tests/hybrid_kw).
  // Node i of the standard run is node h_of[i] of the hybrid run.
  const auto           ds = damage_of(standard), dh = damage_of(hybrid);
  const auto           h_of = same_nodes(hybrid, standard);
  std::vector<unsigned int> s_order(ds.size());
  for (unsigned int i = 0; i < s_order.size(); ++i)
    s_order[i] = i;
  // The same hashes node by node in particle id order: independent of both
  // runs' numbering (cell or lattice order).
  std::vector<unsigned int> s_by_id = s_order, h_by_id(ds.size());
  std::sort(s_by_id.begin(), s_by_id.end(), [&](const unsigned int a, const unsigned int b) {
    return standard.discretization().id[a] < standard.discretization().id[b];
  });
  for (unsigned int k = 0; k < s_by_id.size(); ++k)
    h_by_id[k] = h_of[s_by_id[k]];
  const auto          &x  = standard.discretization().position;
  double               max_diff = 0.;
  std::vector<unsigned int> cracked[2];
  for (std::size_t i = 0; i < ds.size(); ++i)
    {
      max_diff = std::max(max_diff, std::abs(ds[i] - dh[h_of[i]]));
      if (ds[i] >= 0.35)
        cracked[0].push_back(i);
      if (dh[h_of[i]] >= 0.35)
        cracked[1].push_back(i);
    }
  unsigned int unmatched[2] = {0, 0};
  for (unsigned int r = 0; r < 2; ++r)
    for (const unsigned int i : cracked[r])
      {
        bool near = false;
        for (const unsigned int j : cracked[1 - r])
          if (x[i].distance(x[j]) <= 2. * dx * (1. + 1e-12))
            {
              near = true;
              break;
            }
        unmatched[r] += !near;
      }
  double load[3] = {0., 0., 0.};
  if (getloadavg(load, 3) < 0)
    load[0] = -1.;

  std::cout << std::setprecision(4) << "Kalthoff-Winkler, dx = " << dx << " mm, delta = " << delta
            << " mm (m = " << m << "), " << standard.discretization().n_global() << " nodes, "
            << standard.discretization().n_global_bonds() << " bonds, "
            << hybrid.integrator().step() << " steps of " << hybrid.integrator().time_step()
            << " s, sigma = " << sigma << ", switching test every " << interval << " step(s)"
            << (every_step ? " on every bond" :
                bound == "lattice" ? " (amortized, lattice bound)" : " (amortized, StretchBudget)")
            << "\n"
            << "Standard scheme: " << (standard.model().description()) << "\n"
            << "CPU times of " << ratio.size() << " interleaved chunks of " << chunk
            << " steps (load average " << load[0] << ")\n\n"
            << "                               Standard    Adaptive   (source: Table 3.3)\n"
            << "  Initial Omega_s portion [%]  " << std::setw(8) << 100. << "    " << std::setw(8)
            << 100. * initial << "   (100 / 9.72)\n"
            << "  Final Omega_s portion [%]    " << std::setw(8) << 100. << "    " << std::setw(8)
            << 100. * final_fraction << "   (100 / 14.70)\n"
            << "  Stepping CPU time [s]        " << std::setw(8) << ts << "    " << std::setw(8)
            << th << "   (53.25 / 23.59)\n"
            << "  Setup CPU time [s]           " << std::setw(8) << standard_setup << "    "
            << std::setw(8) << hybrid_setup << "\n"
            << "  Crack angle [deg]            " << std::setw(8) << ms.crack_angle << "    "
            << std::setw(8) << mh.crack_angle << "\n"
            << "  Crack length [mm]            " << std::setw(8) << ms.crack_length << "    "
            << std::setw(8) << mh.crack_length << "\n"
            << "  Broken bonds                 " << std::setw(8)
            << standard.model().n_broken_bonds() << "    " << std::setw(8)
            << hybrid.model().n_broken_bonds() << "\n"
            << "  Cracked nodes (damage>=0.35) " << std::setw(8) << cracked[0].size() << "    "
            << std::setw(8) << cracked[1].size() << "   (" << unmatched[0] << " / " << unmatched[1]
            << " farther than 2 dx from the other run's)\n"
            << "  max |damage difference|      " << max_diff << "\n\n"
            << "  Hybrid CPU time in compute_forces: switching test " << parts[0]
            << " s, standard rows " << parts[1] << " s, WLS rows " << parts[2]
            << " s (rest: Verlet update); of the switching test, the bound updates "
            << parts[3] << " s\n"
            << "  Exact node tests of (3.80): " << hm->n_exact_node_tests() << " (bond tests "
            << hm->n_exact_bond_tests() << ")\n\n";
  std::cout << std::setprecision(6) << "kw_hybrid_nodes: " << standard.discretization().n_global()
            << "\nkw_hybrid_m: " << m << "\nkw_hybrid_steps: " << hybrid.integrator().step()
            << "\nkw_hybrid_node_order: " << node_order
            << "\nkw_hybrid_standard_node_order: " << standard_node_order
            << "\nkw_hybrid_load_average: " << load[0]
            << "\nkw_hybrid_standard_seconds: " << ts << "\nkw_hybrid_adaptive_seconds: " << th
            << "\nkw_hybrid_initial_standard_percent: " << 100. * initial
            << "\nkw_hybrid_final_standard_percent: " << 100. * final_fraction
            << "\nkw_hybrid_switch_test_seconds: " << parts[0]
            << "\nkw_hybrid_standard_rows_seconds: " << parts[1]
            << "\nkw_hybrid_wls_rows_seconds: " << parts[2]
            << "\nkw_hybrid_switch_bound_seconds: " << parts[3]
            << "\nkw_hybrid_exact_node_tests: " << hm->n_exact_node_tests()
            << "\nkw_hybrid_exact_bond_tests: " << hm->n_exact_bond_tests()
            << "\nkw_hybrid_overstretched_bonds: " << overstretched
            << "\nkw_hybrid_crack_angle_standard: " << ms.crack_angle
            << "\nkw_hybrid_crack_angle_adaptive: " << mh.crack_angle
            << "\nkw_hybrid_crack_angle_difference: " << mh.crack_angle - ms.crack_angle
            << "\nkw_hybrid_broken_bonds_standard: " << standard.model().n_broken_bonds()
            << "\nkw_hybrid_broken_bonds_adaptive: " << hybrid.model().n_broken_bonds()
            << "\nkw_hybrid_cracked_nodes_unmatched: " << unmatched[0] + unmatched[1]
            << "\nkw_hybrid_speedup_median_chunk: " << median_ratio
            << std::hex << std::setfill('0') << "\nkw_hybrid_state_hash_standard: " << std::setw(16)
            << state_hash(standard, ds, s_order) << "\nkw_hybrid_state_hash_adaptive: " << std::setw(16)
            << state_hash(hybrid, dh, h_of) << "\nkw_hybrid_state_hash_by_id_standard: " << std::setw(16)
            << state_hash(standard, ds, s_by_id) << "\nkw_hybrid_state_hash_by_id_adaptive: " << std::setw(16)
            << state_hash(hybrid, dh, h_by_id) << std::dec << std::setfill(' ')
            << "\nkw_speedup_hybrid_adaptive_over_standard: " << ts / th << std::endl;
  return 0;
}
