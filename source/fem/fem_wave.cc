#include <deal.II/base/quadrature_lib.h>

#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_q1.h>

#include <deal.II/grid/grid_tools.h>

#include <deal.II/lac/lapack_full_matrix.h>

#include <deal.II/numerics/vector_tools.h>

#include <perideal/abc/spectral_radius.h>
#include <perideal/base/exceptions.h>
#include <perideal/fem/fem_wave.h>

#include <chrono>
#include <cmath>
#include <limits>

namespace PeriDEAL
{
  namespace Fem
  {
    void
    FemWaveParameters::declare_parameters(ParameterHandler &prm)
    {
      const FemWaveParameters d;
      prm.declare_entry("Degree", std::to_string(d.degree), Patterns::Integer(1, 2), "FE_Q degree.");
      prm.declare_entry("Wave speed", "1", Patterns::Double(0.), "chi (> 0) of u_tt + 2 d u_t = chi^2 Laplace u.");
      prm.declare_entry("Damping", "0", Patterns::Double(0.), "d >= 0.");
      prm.declare_entry("Time step", "0", Patterns::Double(0.),
                        "Required (> 0); velocity Verlet: at most the lumped-mass CFL bound, "
                        "EBF ABC: at most the bound of its one-step map (both checked at setup).");
      prm.declare_entry("Lumped mass", "true", Patterns::Bool(), "false: consistent mass (Newmark only).");
      prm.declare_entry("Scheme", d.scheme, Patterns::Selection("velocity Verlet|Newmark"),
                        "Explicit damped velocity Verlet (4.62) or implicit average-acceleration Newmark.");
      prm.declare_entry("Preserve constants", "true", Patterns::Bool(),
                        "EBF ABC: extrapolate u - u_i^n so that u = const is kept exactly.");
      prm.declare_entry("Extrapolate velocity", "false", Patterns::Bool(),
                        "EBF ABC: boundary velocities from V_H (4.82) (true, the source) or the "
                        "difference quotient (false).");
      prm.declare_entry("Layer viscosity", "0", Patterns::Double(0.),
                        "Tangential viscosity of the boundary rings (velocity Verlet only; 0: off). "
                        "0.2 makes Verlet + lumped mass + EBF long-run stable on squares (doc/design.md, "
                        "session 13).");
      prm.declare_entry("Layer width", std::to_string(d.layer_width), Patterns::Integer(1), "Rings of the layer.");
      prm.declare_entry("Layer order", std::to_string(d.layer_order), Patterns::Integer(1, 2),
                        "1: ring Laplacian L; 2: L M^-1 L (more selective).");
    }

    void
    FemWaveParameters::parse_parameters(ParameterHandler &prm)
    {
      degree               = prm.get_integer("Degree");
      wave_speed           = prm.get_double("Wave speed");
      damping              = prm.get_double("Damping");
      time_step            = prm.get_double("Time step");
      lumped_mass          = prm.get_bool("Lumped mass");
      scheme               = prm.get("Scheme");
      preserve_constants   = prm.get_bool("Preserve constants");
      extrapolate_velocity = prm.get_bool("Extrapolate velocity");
      layer_viscosity      = prm.get_double("Layer viscosity");
      layer_width          = prm.get_integer("Layer width");
      layer_order          = prm.get_integer("Layer order");
    }

    namespace
    {
      /** Newmark average acceleration. */
      constexpr double newmark_beta = 0.25, newmark_gamma = 0.5;
    } // namespace

    template <int dim>
    FemWave<dim>::FemWave(const Triangulation<dim>    &tria,
                          const FemWaveParameters      &prm,
                          const WaveBoundary            boundary,
                          const Abc::WaveAbcParameters &abc_prm,
                          const Function<dim>          &initial)
      : fe((check_parameter(prm.degree == 1 || prm.degree == 2, "FEM/Degree", prm.degree, "1 or 2"),
            prm.degree))
      , dof_handler(tria)
      , type(boundary)
      , extrapolate_velocity(prm.extrapolate_velocity)
      , lumped(prm.lumped_mass)
      , newmark(prm.scheme == "Newmark")
      , chi(prm.wave_speed)
      , d(prm.damping)
      , dt(prm.time_step)
    {
      check_parameter(chi > 0., "FEM/Wave speed", chi, "> 0");
      check_parameter(d >= 0., "FEM/Damping", d, ">= 0");
      check_parameter(prm.scheme == "velocity Verlet" || prm.scheme == "Newmark", "FEM/Scheme",
                      prm.scheme, "velocity Verlet or Newmark");
      check_parameter(lumped || newmark, "FEM/Lumped mass", std::string("false"),
                      "true with the explicit velocity Verlet (consistent mass: scheme Newmark)");
      dof_handler.distribute_dofs(fe);
      const bool absorbing = type == WaveBoundary::absorbing;

      // Cloud radius (2 node spacings by default) and spacing: needed for
      // the ghost layer before the vectors exist.
      double h = 0.;
      for (const auto &cell : tria.active_cell_iterators())
        if (cell->is_locally_owned())
          h = std::max(h, cell->minimum_vertex_distance());
      h                          = Utilities::MPI::max(h, tria.get_communicator());
      const double           spacing = h / prm.degree;
      Abc::WaveAbcParameters ap      = abc_prm;
      // With a cloud size n the radius is only the search radius of the
      // n nearest cone points (and the ghost layer): 2 n spacings hold
      // them with room on distorted meshes (hyper_ball: the second point
      // along the normal at up to 2.03 h).
      if (ap.cloud_radius <= 0.)
        ap.cloud_radius = (ap.cloud_size > 0 ? 2. * ap.cloud_size : 2.) * spacing * (1. + 1e-9);
      near_field.reinit(dof_handler, absorbing ? ap.cloud_radius : 0.);
      const auto &part = near_field.partitioner;
      near_field.assemble(mass_matrix, stiffness, mass, boundary_mass);
      if (type != WaveBoundary::first_order)
        boundary_mass = 0.;
      boundary_dofs = near_field.boundary;
      if (!newmark)
        {
          const double dt_crit = critical_time_step();
          check_parameter(dt > 0. && dt <= dt_crit, "FEM/Time step", dt,
                          "0 < dt <= " + std::to_string(dt_crit) + " (lumped-mass Verlet bound)");
        }
      else
        check_parameter(dt > 0., "FEM/Time step", dt, "> 0");

      for (auto *x : {&u, &v, &a, &Ku, &u_star, &v_star, &rhs, &tmp})
        x->reinit(part);
      check_parameter(prm.layer_viscosity >= 0. && (prm.layer_viscosity == 0. || !newmark),
                      "FEM/Layer viscosity", prm.layer_viscosity, ">= 0 (> 0: velocity Verlet only)");
      if (prm.layer_viscosity > 0.)
        {
          check_parameter(prm.layer_width >= 1, "FEM/Layer width", prm.layer_width, ">= 1");
          // Graph distance of the DoFs from the boundary, ring by ring: a
          // DoF joins when a stiffness coupling reaches the marked set (the
          // marked entries are all 1 and the couplings of a Q1/Q2 Laplacian
          // row to its neighbours do not cancel at the front).
          const int          first = type == WaveBoundary::first_order ? 0 : 1;
          const int          width = static_cast<int>(prm.layer_width);
          const unsigned int n     = near_field.n_owned();
          DistributedVector  marked(part), front(part), depth(part);
          depth = -1.;
          for (const unsigned int i : boundary_dofs)
            {
              depth.local_element(i)  = 0.;
              marked.local_element(i) = 1.;
            }
          for (int r = 1; r < width + first; ++r)
            {
              marked.update_ghost_values();
              stiffness.vmult(front, marked);
              for (unsigned int i = 0; i < n; ++i)
                if (depth.local_element(i) < 0. && front.local_element(i) != 0.)
                  depth.local_element(i) = r;
              for (unsigned int i = 0; i < n; ++i)
                marked.local_element(i) = depth.local_element(i) >= 0. ? 1. : 0.;
            }
          depth.update_ghost_values();
          // Ring Laplacian: sum over the couplings (i, j) of the stiffness
          // with depth(i) = depth(j) = r of sigma_r |K_ij| (e_i - e_j)
          // (e_i - e_j)^T, sigma_r = 1 - (r - first) / width for
          // first <= r < first + width. Only couplings within a ring, i.e.
          // along the boundary: a field varying only along the normal is
          // not seen at all, a tangentially smooth one weakly (k_t h)^2,
          // the tangential sawtooth of the backward-wave branch strongly.
          // Positive semi-definite; with prescribed boundary DoFs (first =
          // 1) it couples free DoFs only.
          near_field.reinit_matrix(layer_matrix);
          for (unsigned int i = 0; i < n; ++i)
            {
              const int r = static_cast<int>(depth.local_element(i));
              if (r < first || r >= first + width)
                continue;
              const double                  sigma = 1. - static_cast<double>(r - first) / width;
              const types::global_dof_index gi    = near_field.ids[i];
              for (auto it = stiffness.begin(gi); it != stiffness.end(gi); ++it)
                if (it->column() != gi && depth(it->column()) == r)
                  {
                    const double c = sigma * std::abs(it->value());
                    layer_matrix.add(gi, gi, c);
                    layer_matrix.add(gi, it->column(), -c);
                  }
            }
          layer_matrix.compress(VectorOperation::add);
          layer_v.reinit(part);
          layer_force.reinit(part);
          has_layer = true;
        }
      check_parameter(prm.layer_order == 1 || prm.layer_order == 2, "FEM/Layer order", prm.layer_order, "1 or 2");
      layer_order = prm.layer_order;
      layer_eta   = prm.layer_viscosity * chi * std::pow(spacing, 2 * prm.layer_order - 1);
      VectorTools::interpolate(dof_handler, initial, u);
      if (type == WaveBoundary::dirichlet)
        for (const unsigned int i : boundary_dofs)
          u.local_element(i) = 0.;
      u.update_ghost_values();
      const unsigned int n_local = near_field.points.size();
      u_old.assign(u.begin(), u.begin() + n_local);
      v_old.assign(n_local, 0.);

      // Newmark in displacement form: A u^{n+1} = rhs with
      // A = (c0 + 2 d c1) M + chi^2 K + chi (c1 + d) B, identity rows for
      // prescribed (Dirichlet or absorbing) DoFs; M for the initial a.
      if (!lumped || newmark)
        {
          const TrilinosWrappers::SolverDirect::AdditionalData ad(false, "Amesos_Klu");
          if (!lumped)
            {
              mass_solver = std::make_unique<TrilinosWrappers::SolverDirect>(solver_control, ad);
              mass_solver->initialize(mass_matrix);
            }
          const double c0 = 1. / (newmark_beta * dt * dt), c1 = newmark_gamma / (newmark_beta * dt);
          system.copy_from(mass_matrix);
          if (lumped)
            {
              system = 0.;
              for (unsigned int l = 0; l < near_field.n_owned(); ++l)
                system.set(near_field.ids[l], near_field.ids[l], mass.local_element(l));
              system.compress(VectorOperation::insert);
            }
          system *= c0 + 2. * d * c1;
          system.add(chi * chi, stiffness);
          for (unsigned int l = 0; l < near_field.n_owned(); ++l)
            if (boundary_mass.local_element(l) != 0.)
              system.add(near_field.ids[l], near_field.ids[l], chi * (c1 + d) * boundary_mass.local_element(l));
          system.compress(VectorOperation::add);
          if (type != WaveBoundary::first_order)
            {
              std::vector<types::global_dof_index> rows;
              for (const unsigned int l : boundary_dofs)
                rows.push_back(near_field.ids[l]);
              system.clear_rows(rows, 1.);
            }
          solver = std::make_unique<TrilinosWrappers::SolverDirect>(solver_control, ad);
          solver->initialize(system);
        }
      set_acceleration();

      if (!absorbing)
        return;
      // Measured: with FE_Q(2) and velocity Verlet the EBF update has
      // one-step spectral radius 1.008 (dt = 0.02, h = 0.5; 1.0002 even with
      // a truncated pseudo-inverse), against 1.0025 for FE_Q(1) which
      // truncation fixes.
      check_parameter(prm.degree == 1 || (newmark && !lumped), "FEM/Degree", prm.degree,
                      "1 with the EBF absorbing boundary and velocity Verlet or lumped mass (FE_Q(2) + EBF is "
                      "unstable there: one-step spectral radius > 1); FE_Q(2) needs Newmark with consistent mass");
      check_parameter(ap.dispersion == "local" || ap.dispersion == "discrete",
                      "Absorbing boundary/Dispersion relation", ap.dispersion,
                      "local or discrete for a FEM near field");
      if (ap.dispersion == "local")
        relation = Abc::WaveDispersion<dim>::local(chi, d);
      else
        {
          // The semi-discrete symbol of the Q1 scheme from the stiffness
          // row of the DoF nearest the centre (of all ranks), divided by the
          // lumped mass or by the symbol of the consistent mass row. Q2 has
          // vertex, edge and cell DoFs with different rows: no single-row
          // symbol.
          check_parameter(prm.degree == 1, "FEM/Degree", prm.degree,
                          "1 for Dispersion relation = discrete (otherwise use local)");
          Point<dim> centre;
          for (unsigned int l = 0; l < near_field.n_owned(); ++l)
            centre += near_field.points[l];
          for (unsigned int k = 0; k < dim; ++k)
            centre[k] = Utilities::MPI::sum(centre[k], near_field.comm) / dof_handler.n_dofs();
          std::pair<double, types::global_dof_index> best(std::numeric_limits<double>::max(), 0);
          for (unsigned int l = 0; l < near_field.n_owned(); ++l)
            best = std::min(best, std::make_pair(near_field.points[l].distance(centre), near_field.ids[l]));
          for (const auto &other : Utilities::MPI::all_gather(near_field.comm, best))
            best = std::min(best, other);
          // Stiffness row (offsets, -chi^2 K_ij) and, for the consistent
          // mass, the mass row (offsets, M_ij) and M_ii; lumped: the row
          // divided by the lumped mass, mass symbol 1.
          using Row = std::pair<std::vector<Tensor<1, dim>>, std::vector<double>>;
          std::pair<Row, std::pair<Row, double>> rows;
          if (near_field.owned.is_element(best.second))
            {
              const unsigned int c = near_field.partitioner->global_to_local(best.second);
              for (auto it = stiffness.begin(best.second); it != stiffness.end(best.second); ++it)
                if (it->column() != best.second)
                  {
                    const unsigned int j = near_field.partitioner->global_to_local(it->column());
                    rows.first.first.push_back(near_field.points[j] - near_field.points[c]);
                    // Lumped: divided here (as before session 19, bitwise).
                    rows.first.second.push_back(-chi * chi * it->value() /
                                                (lumped ? mass.local_element(c) : 1.));
                  }
              rows.second.second = 1.;
              if (!lumped)
                {
                  rows.second.second = mass_matrix.el(best.second, best.second);
                  for (auto it = mass_matrix.begin(best.second); it != mass_matrix.end(best.second); ++it)
                    if (it->column() != best.second)
                      {
                        const unsigned int j = near_field.partitioner->global_to_local(it->column());
                        rows.second.first.first.push_back(near_field.points[j] - near_field.points[c]);
                        rows.second.first.second.push_back(it->value());
                      }
                }
            }
          for (const auto &other : Utilities::MPI::all_gather(near_field.comm, rows))
            if (!other.first.first.empty())
              rows = other;
          relation = Abc::WaveDispersion<dim>::stencil(rows.first.first, rows.first.second, d,
                                                       lumped ? "discrete Q1 lumped" : "discrete Q1 consistent",
                                                       rows.second.second, rows.second.first.first,
                                                       rows.second.first.second);
        }
      abc.reinit(near_field.points, near_field.ids, boundary_dofs, near_field.normals, relation, dt, spacing, ap,
                 near_field.comm);
      constant_defect.assign(boundary_dofs.size(), 0.);
      if (prm.preserve_constants)
        {
          const std::vector<double> ones(n_local, 1.), zeros(n_local, 0.);
          abc.compute(ones.data(), ones.data(), zeros.data(), zeros.data(), u_abc, v_abc);
          for (unsigned int c = 0; c < u_abc.size(); ++c)
            constant_defect[c] = 1. - u_abc[c];
        }
      // Optional global stability guard (the cloud guards of Sect. 4.2.3 are
      // not sufficient, see doc/design.md); serial runs only.
      const unsigned int n = dof_handler.n_dofs();
      if (ap.spectral_check_size > 0 && Utilities::MPI::n_mpi_processes(near_field.comm) == 1 &&
          (newmark ? 3 : 2) * n + 2 * abc.cloud_points().size() <= ap.spectral_check_size)
        {
          unsigned int n_up = 0;
          spectral_radius   = one_step_spectral_radius(ap.spectral_check_size, &n_up);
          if (spectral_radius > ap.max_spectral_radius)
            throw ParameterError("Absorbing boundary/Pseudo-inverse tolerance",
                                 std::to_string(ap.pseudo_inverse_tolerance),
                                 "a value for which the one-step spectral radius (here " +
                                   std::to_string(spectral_radius) + ", " + std::to_string(n_up) +
                                   " eigenvalues > 1) is <= " + std::to_string(ap.max_spectral_radius));
        }
    }

    template <int dim>
    double
    FemWave<dim>::critical_time_step() const
    {
      double lmax = 0.;
      for (unsigned int l = 0; l < near_field.n_owned(); ++l)
        {
          const auto i   = near_field.ids[l];
          double     row = 0.;
          for (auto it = stiffness.begin(i); it != stiffness.end(i); ++it)
            row += std::abs(it->value());
          lmax = std::max(lmax, chi * chi * row / mass.local_element(l));
        }
      return 2. / std::sqrt(Utilities::MPI::max(lmax, near_field.comm));
    }

    template <int dim>
    void
    FemWave<dim>::apply_mass(const DistributedVector &x, DistributedVector &y) const
    {
      if (lumped)
        for (unsigned int l = 0; l < near_field.n_owned(); ++l)
          y.local_element(l) = mass.local_element(l) * x.local_element(l);
      else
        mass_matrix.vmult(y, x);
    }

    template <int dim>
    void
    FemWave<dim>::set_acceleration()
    {
      // M a = -chi^2 K u - 2 d M v - chi B (v + d u).
      u.update_ghost_values();
      stiffness.vmult(Ku, u);
      const unsigned int n = near_field.n_owned();
      apply_layer_viscosity();
      for (unsigned int i = 0; i < n; ++i)
        tmp.local_element(i) = -chi * chi * Ku.local_element(i) -
                               chi * boundary_mass.local_element(i) * (v.local_element(i) + d * u.local_element(i)) -
                               (has_layer ? layer_force.local_element(i) : 0.);
      if (lumped)
        for (unsigned int i = 0; i < n; ++i)
          a.local_element(i) = tmp.local_element(i) / mass.local_element(i);
      else
        mass_solver->solve(a, tmp);
      a.add(-2. * d, v);
      v.update_ghost_values();
    }

    template <int dim>
    void
    FemWave<dim>::apply_layer_viscosity()
    {
      if (!has_layer)
        return;
      // L positive semi-definite: v . (eta L v) >= 0 and v . (eta L M^-1 L v) >= 0.
      for (unsigned int i = 0; i < near_field.n_owned(); ++i)
        layer_v.local_element(i) = v.local_element(i);
      layer_v.update_ghost_values();
      layer_matrix.vmult(layer_force, layer_v);
      for (unsigned int k = 1; k < layer_order; ++k)
        {
          for (unsigned int i = 0; i < near_field.n_owned(); ++i)
            layer_v.local_element(i) = layer_force.local_element(i) / mass.local_element(i);
          layer_v.update_ghost_values();
          layer_matrix.vmult(layer_force, layer_v);
        }
      layer_force *= layer_eta;
    }

    template <int dim>
    double
    FemWave<dim>::one_step_spectral_radius(const unsigned int    max_size,
                                           unsigned int         *n_unstable,
                                           std::complex<double> *dominant)
    {
      check_parameter(Utilities::MPI::n_mpi_processes(near_field.comm) == 1, "MPI processes",
                      Utilities::MPI::n_mpi_processes(near_field.comm), "1 for the dense spectral radius check");
      const unsigned int               n = u.size();
      const std::vector<unsigned int> &c = abc.cloud_points();
      const bool                       absorbing = type == WaveBoundary::absorbing;
      const unsigned int               n_fields  = newmark ? 3 : 2;
      const unsigned int               m = n_fields * n + (absorbing ? 2 * c.size() : 0);
      check_parameter(m <= max_size, "State size of the spectral radius check", m,
                      "<= " + std::to_string(max_size) + " (dense eigenvalue problem)");
      const DistributedVector   u0 = u, v0 = v, a0 = a;
      const std::vector<double> uo0 = u_old, vo0 = v_old;
      const double              t0 = t, abc0 = abc_seconds, step0 = step_seconds;
      LAPACKFullMatrix<double>  map(m, m);
      const unsigned int        cs = n_fields * n;
      for (unsigned int col = 0; col < m; ++col)
        {
          u = 0.;
          v = 0.;
          a = 0.;
          if (absorbing)
            for (const unsigned int q : c)
              u_old[q] = v_old[q] = 0.;
          if (col < n)
            u[col] = 1.;
          else if (col < 2 * n)
            v[col - n] = 1.;
          else if (col < cs)
            a[col - 2 * n] = 1.;
          else if (col < cs + c.size())
            u_old[c[col - cs]] = 1.;
          else
            v_old[c[col - cs - c.size()]] = 1.;
          if (!newmark)
            set_acceleration();
          advance();
          for (unsigned int i = 0; i < n; ++i)
            {
              map(i, col)     = u[i];
              map(n + i, col) = v[i];
              if (newmark)
                map(2 * n + i, col) = a[i];
            }
          if (absorbing)
            for (unsigned int q = 0; q < c.size(); ++q)
              {
                map(cs + q, col)            = u_old[c[q]];
                map(cs + c.size() + q, col) = v_old[c[q]];
              }
        }
      u            = u0;
      v            = v0;
      a            = a0;
      u_old        = uo0;
      v_old        = vo0;
      t            = t0;
      abc_seconds  = abc0;
      step_seconds = step0;
      return Abc::spectral_radius(map, n_unstable, dominant);
    }

    template <int dim>
    void
    FemWave<dim>::extrapolate_boundary()
    {
      // Only the cloud entries of the previous level are read.
      if (extrapolate_velocity)
        {
          abc.compute(u.begin(), u_old.data(), v.begin(), v_old.data(), u_abc, v_abc);
          for (const unsigned int q : abc.cloud_points())
            v_old[q] = v.local_element(q);
        }
      else
        abc.compute_values(u.begin(), u_old.data(), u_abc);
      for (const unsigned int q : abc.cloud_points())
        u_old[q] = u.local_element(q);
    }

    template <int dim>
    void
    FemWave<dim>::advance()
    {
      using clock      = std::chrono::steady_clock;
      const auto start = clock::now();
      if (type == WaveBoundary::absorbing)
        {
          const auto abc_start = clock::now();
          extrapolate_boundary();
          abc_seconds += std::chrono::duration<double>(clock::now() - abc_start).count();
        }
      if (newmark)
        advance_newmark();
      else
        advance_verlet();
      t += dt;
      v.update_ghost_values();
      step_seconds += std::chrono::duration<double>(clock::now() - start).count();
    }

    template <int dim>
    void
    FemWave<dim>::advance_verlet()
    {
      const unsigned int n     = near_field.n_owned();
      const double       half  = 0.5 * dt;
      const auto        &nodes = abc.absorbing_points();
      for (unsigned int i = 0; i < n; ++i)
        {
          u.local_element(i) += dt * (v.local_element(i) + half * a.local_element(i));
          v.local_element(i) += half * a.local_element(i);
        }
      if (type == WaveBoundary::absorbing)
        for (unsigned int c = 0; c < nodes.size(); ++c)
          u.local_element(nodes[c]) = u_abc[c] + constant_defect[c] * u_old[nodes[c]];
      else if (type == WaveBoundary::dirichlet)
        for (const unsigned int i : boundary_dofs)
          u.local_element(i) = 0.;
      u.update_ghost_values();
      stiffness.vmult(Ku, u);
      // The layer force from v^{n+1/2} (explicit).
      apply_layer_viscosity();
      // M a = -chi^2 K u - 2 d M v - chi B (v + d u) (- the layer force of v^{n+1/2}
      // in the layer); B = 0 unless first order.
      for (unsigned int i = 0; i < n; ++i)
        {
          const double b = chi * boundary_mass.local_element(i) / mass.local_element(i);
          const double f = -(chi * chi * Ku.local_element(i) +
                             (has_layer ? layer_force.local_element(i) : 0.)) /
                             mass.local_element(i) -
                           b * d * u.local_element(i);
          v.local_element(i) = (v.local_element(i) + half * f) / (1. + dt * d + half * b);
          a.local_element(i) = f - (2. * d + b) * v.local_element(i);
        }
      if (type == WaveBoundary::absorbing)
        for (unsigned int c = 0; c < nodes.size(); ++c)
          v.local_element(nodes[c]) =
            extrapolate_velocity ? v_abc[c] : (u.local_element(nodes[c]) - u_old[nodes[c]]) / dt;
      else if (type == WaveBoundary::dirichlet)
        for (const unsigned int i : boundary_dofs)
          v.local_element(i) = a.local_element(i) = 0.;
    }

    template <int dim>
    void
    FemWave<dim>::advance_newmark()
    {
      // Displacement form: u* = u + dt v + dt^2 (1/2 - beta) a,
      // v* = v + (1 - gamma) dt a, a^{n+1} = c0 (u^{n+1} - u*),
      // v^{n+1} = v* + gamma dt a^{n+1}; the equation of motion at t^{n+1}
      // gives A u^{n+1} = M ((c0 + 2 d c1) u* - 2 d v*) + chi B (c1 u* - v*).
      const unsigned int n  = near_field.n_owned();
      const double       c0 = 1. / (newmark_beta * dt * dt), c1 = newmark_gamma / (newmark_beta * dt);
      for (unsigned int i = 0; i < n; ++i)
        {
          const double us = u.local_element(i) + dt * v.local_element(i) +
                            dt * dt * (0.5 - newmark_beta) * a.local_element(i);
          const double vs = v.local_element(i) + (1. - newmark_gamma) * dt * a.local_element(i);
          u_star.local_element(i) = us;
          v_star.local_element(i) = vs;
          tmp.local_element(i)    = (c0 + 2. * d * c1) * us - 2. * d * vs;
        }
      apply_mass(tmp, rhs);
      for (unsigned int i = 0; i < n; ++i)
        rhs.local_element(i) +=
          chi * boundary_mass.local_element(i) * (c1 * u_star.local_element(i) - v_star.local_element(i));
      const auto &nodes = abc.absorbing_points();
      if (type == WaveBoundary::absorbing)
        for (unsigned int c = 0; c < nodes.size(); ++c)
          rhs.local_element(nodes[c]) = u_abc[c] + constant_defect[c] * u_old[nodes[c]];
      else if (type == WaveBoundary::dirichlet)
        for (const unsigned int i : boundary_dofs)
          rhs.local_element(i) = 0.;
      u.zero_out_ghost_values();
      solver->solve(u, rhs);
      u.update_ghost_values();
      for (unsigned int i = 0; i < n; ++i)
        {
          a.local_element(i) = c0 * (u.local_element(i) - u_star.local_element(i));
          v.local_element(i) = v_star.local_element(i) + newmark_gamma * dt * a.local_element(i);
        }
    }

    template <int dim>
    double
    FemWave<dim>::energy(const std::function<bool(const Point<dim> &)> &inside) const
    {
      const QGauss<dim>           q(fe.degree + 1);
      FEValues<dim>               fv(fe, q, update_values | update_gradients | update_JxW_values);
      std::vector<double>         vq(q.size());
      std::vector<Tensor<1, dim>> gq(q.size());
      double                      e = 0.;
      for (const auto &cell : dof_handler.active_cell_iterators())
        if (cell->is_locally_owned() && inside(cell->center()))
          {
            fv.reinit(cell);
            fv.get_function_values(v, vq);
            fv.get_function_gradients(u, gq);
            for (unsigned int k = 0; k < q.size(); ++k)
              e += 0.5 * (vq[k] * vq[k] + chi * chi * gq[k] * gq[k]) * fv.JxW(k);
          }
      return Utilities::MPI::sum(e, near_field.comm);
    }

    template <int dim>
    double
    FemWave<dim>::value_at(const Point<dim> &p) const
    {
      // The owning rank of the cell containing p evaluates; serial: directly.
      if (Utilities::MPI::n_mpi_processes(near_field.comm) == 1)
        return VectorTools::point_value(dof_handler, u, p);
      double value = 0., found = 0.;
      try
        {
          const auto [cell, ref] = GridTools::find_active_cell_around_point(MappingQ1<dim>(), dof_handler, p);
          if (cell.state() == IteratorState::valid && cell->is_locally_owned())
            {
              std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
              cell->get_dof_indices(dofs);
              for (unsigned int i = 0; i < dofs.size(); ++i)
                value += u(dofs[i]) * fe.shape_value(i, ref);
              found = 1.;
            }
        }
      catch (...)
        {}
      const double n_found = Utilities::MPI::sum(found, near_field.comm);
      return n_found > 0. ? Utilities::MPI::sum(value, near_field.comm) / n_found : 0.;
    }

    template class FemWave<1>;
    template class FemWave<2>;
  } // namespace Fem
} // namespace PeriDEAL
