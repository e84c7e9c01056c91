// step-14: PD corrosion of a metal in an electrolyte with two ionic species
// (the nonlocal Nernst-Planck-Poisson system, NNPP, dissertation Sect. 2.3.4).
//
// The idea of this step: electromigration. A dissolving metal releases
// cations M (z = 2) into an electrolyte that also holds anions A (z = -1).
// Each species diffuses with its own (phase-dependent) diffusivity, and the
// charge sum_k z_k F C_k drives the nonlocal Poisson equation for phi, whose
// gradient pulls the ions along: the two species no longer move
// independently. We run the same parameter file (read in the format of the
// perideal driver, Problem = nnpp) twice: as given, and with z = 0 for both
// species (pure diffusion, phi = 0), and compare.
//
// The independent check: with z = 0 the metal species obeys exactly the
// library's bi-material PD corrosion model (Model/Type = corrosion,
// DiffusionSolver: its own operator, Jacobian, Newton loop and phase rule),
// with micro-diffusivities kappa = K1 D and the NNPP kernel exponent
// n_d + 2 q1. The two codes share only the lattice; they must agree to
// round-off, phase change by phase change.
//
// Output: output/migration and output/diffusion (the driver's VTU + CSV),
// output/profiles.csv, output/solid_volume.csv and output/step-14.png.
// The program returns non-zero unless the checks at the end hold.

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/utilities.h>

#include <perideal/base/exceptions.h>
#include <perideal/io/plot.h>
#include <perideal/time_stepping/diffusion_solver.h>
#include <perideal/time_stepping/nnpp_run.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>

using namespace dealii;
using namespace PeriDEAL;

namespace Step14
{
  // Interior nodes of a 1D run: x, C_M, C_A, phi, sorted by x (gathered on all ranks).
  using Profile = std::vector<std::array<double, 4>>;

  Profile
  gather_profile(const Discretization<1> &disc, const std::vector<const PeriDEAL::Vector *> &fields)
  {
    std::vector<double> packed;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<1>::interior)
        {
          packed.push_back(disc.position[i][0]);
          for (unsigned int f = 0; f < 3; ++f)
            packed.push_back(f < fields.size() ? fields[f]->local_element(i) : 0.);
        }
    Profile p;
    for (const auto &part : Utilities::MPI::all_gather(disc.get_mpi_communicator(), packed))
      for (std::size_t j = 0; j + 3 < part.size(); j += 4)
        p.push_back({{part[j], part[j + 1], part[j + 2], part[j + 3]}});
    std::sort(p.begin(), p.end());
    return p;
  }

  // First recorded time at which the solid is gone (or -1).
  double
  vanishing_time(const std::vector<NnppDiagnostics> &h)
  {
    for (const auto &d : h)
      if (d.solid_volume == 0.)
        return d.time;
    return -1.;
  }

  struct Checks
  {
    unsigned int failures = 0;
    void
    operator()(const bool ok, const std::string &what)
    {
      if (Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0)
        std::cout << (ok ? "  ok    " : "  FAIL  ") << what << std::endl;
      failures += ok ? 0 : 1;
    }
  };
} // namespace Step14

int
main(int argc, char **argv)
{
  using namespace Step14;
  try
    {
      Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
      const MPI_Comm comm = MPI_COMM_WORLD;
      const bool     root = Utilities::MPI::this_mpi_process(comm) == 0;

      // The driver's parameter set (step-14.prm is also a driver input).
      ParameterHandler prm;
      prm.declare_entry("Dimension", "1", Patterns::Integer(1, 1), "step-14 is 1D.");
      prm.declare_entry("Problem", "nnpp", Patterns::Selection("nnpp"), "step-14: nnpp only.");
      DiffusionRunParameters<2>::declare_parameters(prm);
      NnppRunParameters<2>::declare_parameters(prm);
      prm.parse_input(argc > 1 ? argv[1] : "step-14.prm");
      NnppRunParameters<1> p;
      p.parse_parameters(prm);
      check_parameter(p.model.n_species() == 2 && p.model.phase_species == 0, "NNPP/Valences",
                      p.model.n_species(), "two species, the metal first (Phase species = 0)");
      const std::string out = p.output_directory.empty() ? std::string("output") : p.output_directory;
      if (root)
        std::filesystem::create_directories(out);
      MPI_Barrier(comm);

      // @sect3{Run 1: with electromigration (the parameter file as given)}
      Profile migration_profile, diffusion_profile;
      double  k1 = 0.;
      p.output_directory = out + "/migration";
      if (root)
        std::cout << "NNPP, valences " << p.model.valence[0] << ", " << p.model.valence[1] << std::endl;
      const auto migration = run_nnpp<1>(p, comm, true, [&](const auto &disc, const auto &s) {
        migration_profile = gather_profile(disc, {&s.C[0], &s.C[1], &s.phi});
      });

      // @sect3{Run 2: the same with z = 0 (pure diffusion)}
      NnppRunParameters<1> p0 = p;
      p0.model.valence        = {0., 0.};
      p0.output_directory     = out + "/diffusion";
      if (root)
        std::cout << "NNPP, valences 0, 0" << std::endl;
      const auto diffusion = run_nnpp<1>(p0, comm, true, [&](const auto &disc, const auto &s) {
        diffusion_profile = gather_profile(disc, {&s.C[0], &s.C[1], &s.phi});
        k1                = s.nnpp_operator().k1();
      });

      // @sect3{Run 3: the library's PD corrosion model for the metal}
      // No constraint layer: missing neighbours are absent, as the closed
      // NNPP species (bonds to the layer carry no flux) on the same nodes.
      DiffusionRunParameters<1> dp;
      dp.domain                  = p.domain;
      dp.lattice                 = p.lattice;
      dp.lattice.layer_thickness = 0.;
      dp.model.type              = "corrosion";
      dp.model.omega             = p.model.omega;
      dp.model.exponent          = 1. + 2. * p.model.q1; // (2.49): n_d + 2 q
      dp.model.kappa_liquid      = k1 * p.model.diffusivity[0][0];
      dp.model.kappa_interface   = k1 * p.model.diffusivity[0][1];
      dp.model.kappa_solid       = k1 * p.model.diffusivity[0][2];
      dp.model.saturation        = p.model.saturation;
      dp.initial_condition       = p.initial_concentrations[0];
      dp.constants               = p.constants;
      dp.scheme                  = "backward Euler";
      dp.time_step               = p.model.time_step;
      dp.end_time                = p.end_time;
      dp.linear_tolerance        = 1e-14;
      dp.newton_tolerance        = 1e-13;
      dp.preconditioner          = "AMG";
      DiffusionSolver<1> corrosion(comm, dp);
      corrosion.setup();
      std::vector<double> corrosion_solid{corrosion.diagnostics().solid_volume};
      while (corrosion.step() < corrosion.n_steps())
        {
          corrosion.advance();
          corrosion_solid.push_back(corrosion.diagnostics().solid_volume);
        }
      const Profile corrosion_profile =
        gather_profile(corrosion.discretization(), {&corrosion.solution()});

      // @sect3{Comparison}
      double max_c_diff = 0., max_c = 0.;
      bool   same_nodes = corrosion_profile.size() == diffusion_profile.size();
      for (std::size_t j = 0; same_nodes && j < corrosion_profile.size(); ++j)
        {
          same_nodes = same_nodes && std::abs(corrosion_profile[j][0] - diffusion_profile[j][0]) < 1e-12;
          max_c_diff = std::max(max_c_diff, std::abs(corrosion_profile[j][1] - diffusion_profile[j][1]));
          max_c      = std::max(max_c, std::abs(corrosion_profile[j][1]));
        }
      // Solid volumes step by step (the NNPP series has one row per Time series interval).
      unsigned int phase_mismatches = 0;
      double       max_solid_diff   = 0.;
      const double dt               = p.model.time_step;
      for (const auto &d : diffusion)
        {
          const auto n = (std::size_t)std::llround(d.time / dt);
          if (n < corrosion_solid.size())
            {
              const double diff = std::abs(d.solid_volume - corrosion_solid[n]);
              max_solid_diff    = std::max(max_solid_diff, diff);
              phase_mismatches += diff > 1e-12;
            }
          else
            ++phase_mismatches;
        }

      auto mass_change = [](const std::vector<NnppDiagnostics> &h, const unsigned int k) {
        double dev = 0.;
        for (const auto &d : h)
          dev = std::max(dev, std::abs(d.amount[k] - h.front().amount[k]) / h.front().amount[k]);
        return dev;
      };
      double max_phi_migration = 0., max_phi_diffusion = 0., max_solid_gap = 0.;
      for (const auto &d : migration)
        max_phi_migration = std::max(max_phi_migration, d.max_abs_phi);
      for (const auto &d : diffusion)
        max_phi_diffusion = std::max(max_phi_diffusion, d.max_abs_phi);
      for (std::size_t j = 0; j < std::min(migration.size(), diffusion.size()); ++j)
        max_solid_gap =
          std::max(max_solid_gap, std::abs(migration[j].solid_volume - diffusion[j].solid_volume));
      const double node_volume = p.lattice.dx;
      // Where the released metal went: amount of M in the electrolyte x > x_front(0) + 0.25.
      auto far_metal = [](const Profile &pr, const double x) {
        double m = 0.;
        for (const auto &r : pr)
          m += r[0] > x ? r[1] : 0.;
        return m;
      };
      const double x_far = 0.75;
      // Local charge imbalance |C_A - 2 C_M| = |sum z_k C_k| / 1 away from the grounded ends.
      auto imbalance = [&p](const Profile &pr) {
        double m = 0.;
        for (const auto &r : pr)
          if (r[0] > 0.1 * p.domain->bounding_box().get_boundary_points().second[0] &&
              r[0] < 0.9 * p.domain->bounding_box().get_boundary_points().second[0])
            m = std::max(m, std::abs(r[2] - 2. * r[1]));
        return m;
      };

      if (root)
        {
          const double dx = p.lattice.dx;
          std::cout << std::setprecision(4) << "\nK1 = " << k1 << ", nodes " << diffusion_profile.size()
                    << ", steps " << corrosion.n_steps() << "\n"
                    << "                         with migration   z = 0\n"
                    << "  solid gone at t        " << std::setw(14) << vanishing_time(migration)
                    << "   " << vanishing_time(diffusion) << "\n"
                    << "  max |phi|              " << std::setw(14) << max_phi_migration << "   "
                    << max_phi_diffusion << "\n"
                    << "  M beyond x = " << x_far << " at end " << std::setw(10)
                    << dx * far_metal(migration_profile, x_far) << "   "
                    << dx * far_metal(diffusion_profile, x_far) << "\n"
                    << "  max |C_A - 2 C_M| inner 80 % " << std::setw(8) << imbalance(migration_profile)
                    << "   " << imbalance(diffusion_profile) << "\n"
                    << std::scientific << std::setprecision(2)
                    << "  max rel. mass change M " << std::setw(14) << mass_change(migration, 0)
                    << "   " << mass_change(diffusion, 0) << "\n"
                    << "  max rel. mass change A " << std::setw(14) << mass_change(migration, 1)
                    << "   " << mass_change(diffusion, 1) << "\n"
                    << "  z = 0 vs PD corrosion model: max |C diff| " << max_c_diff << " (max C "
                    << max_c << "), solid volume max diff " << max_solid_diff << " over "
                    << diffusion.size() << " rows\n"
                    << "  max solid volume gap migration vs z = 0: " << max_solid_gap << " ("
                    << std::llround(max_solid_gap / node_volume) << " nodes)\n"
                    << std::endl;

          // CSVs and the plot.
          std::ofstream sv(out + "/solid_volume.csv");
          sv << "time,solid_migration,solid_z0,max_abs_phi\n" << std::setprecision(10);
          for (std::size_t j = 0; j < std::min(migration.size(), diffusion.size()); ++j)
            sv << migration[j].time << "," << migration[j].solid_volume << ","
               << diffusion[j].solid_volume << "," << migration[j].max_abs_phi << "\n";
          sv.close();
          std::ofstream pf(out + "/profiles.csv");
          pf << "x,CM_migration,CA_migration,phi_migration,CM_z0,CA_z0\n" << std::setprecision(10);
          for (std::size_t j = 0; j < std::min(migration_profile.size(), diffusion_profile.size()); ++j)
            pf << migration_profile[j][0] << "," << migration_profile[j][1] << ","
               << migration_profile[j][2] << "," << migration_profile[j][3] << ","
               << diffusion_profile[j][1] << "," << diffusion_profile[j][2] << "\n";
          pf.close();
          const std::string s = "'" + out + "/solid_volume.csv'", f = "'" + out + "/profiles.csv'";
          run_gnuplot(out + "/plot.gp",
                      gnuplot_png_preamble(out + "/step-14.png") +
                        "set datafile separator ','\nset multiplot layout 1,2\n"
                        "set xlabel 'time'\nset ylabel 'solid volume'\n"
                        "plot " + s + " using 1:2 with lines lw 2 title 'z = 2, -1', '' using 1:3 "
                        "with lines lw 2 dt 2 title 'z = 0'\n"
                        "set xlabel 'x'\nset ylabel 'C at the end time'\nset key top right\n"
                        "plot " + f + " using 1:2 with lines lw 2 title 'M, z = 2', '' using 1:3 "
                        "with lines lw 2 title 'A, z = -1', '' using 1:5 with lines lw 2 dt 2 "
                        "title 'M, z = 0', '' using 1:6 with lines lw 2 dt 2 title 'A, z = 0'\n"
                        "unset multiplot\n",
                      out + "/step-14.png");
        }

      // @sect3{Checks}
      Checks check;
      // Bond fluxes are antisymmetric and the species closed: each mass is
      // conserved up to the Newton/linear tolerances (1e-12 relative).
      check(std::max({mass_change(migration, 0), mass_change(migration, 1), mass_change(diffusion, 0),
                      mass_change(diffusion, 1)}) < 1e-11,
            "mass of each species conserved to 1e-11 (both runs)");
      check(same_nodes, "z = 0 and PD corrosion model use the same interior nodes");
      check(phase_mismatches == 0, "z = 0: solid volume equals the PD corrosion model's at every step");
      // Both codes solve the same linear system per step; each stops at a
      // relative residual <= 1e-12 (NNPP Newton) / 1e-13, so 1e-11 bounds the
      // accumulated stopping error (measured: 3e-15, round-off).
      check(max_c_diff < 1e-11 * max_c,
            "z = 0: metal concentration equals the PD corrosion model's to 1e-11 (relative)");
      check(max_phi_diffusion == 0., "z = 0: no charge, phi = 0");
      check(max_phi_migration > 1e-3, "with z = 2, -1 a potential builds up");
      check(max_solid_gap >= node_volume * (1. - 1e-12),
            "electromigration changes the dissolution (solid volumes differ by a node or more)");
      // The Poisson coupling drives towards electroneutrality (C_A = 2 C_M):
      // the imbalance must be clearly smaller than without charge.
      check(imbalance(migration_profile) < 0.5 * imbalance(diffusion_profile),
            "with migration the ions stay closer to electroneutral (|C_A - 2 C_M| halved or better)");
      return check.failures == 0 ? 0 : 1;
    }
  catch (std::exception &e)
    {
      std::cerr << "step-14: error: " << e.what() << std::endl;
      return 1;
    }
}
