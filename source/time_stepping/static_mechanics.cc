#include <deal.II/base/function_parser.h>
#include <deal.II/base/timer.h>

#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/solver_gmres.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparsity_pattern.h>

#include <perideal/base/exceptions.h>
#include <perideal/base/expressions.h>
#include <perideal/io/node_output.h>
#include <perideal/models/stiffness.h>
#include <perideal/time_stepping/static_mechanics.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>

namespace PeriDEAL
{
  namespace
  {
    // A parsed muparser expression of x, y, z as a function object; a
    // shared_ptr because FunctionParser is not copyable.
    template <int dim>
    std::shared_ptr<FunctionParser<dim>>
    parse_expressions(const std::vector<std::string> &parts, const std::string &parameter)
    {
      auto f = std::make_shared<FunctionParser<dim>>(parts.size());
      try
        {
          f->initialize(FunctionParser<dim>::default_variable_names(), parts,
                        expression_constants(dim));
          for (unsigned int c = 0; c < parts.size(); ++c)
            f->value(Point<dim>(), c);
        }
      catch (std::exception &)
        {
          std::string text;
          for (const auto &part : parts)
            text += (text.empty() ? "" : "; ") + part;
          throw ParameterError(parameter, text, "muparser expressions in x, y, z");
        }
      return f;
    }

    // "f1; f2[; f3]" (the first dim are used) as a vector field.
    template <int dim>
    typename StaticMechanicsParameters<dim>::Field
    vector_field(const std::string &text, const std::string &parameter)
    {
      auto parts = Utilities::split_string_list(text, ';');
      check_parameter(parts.size() >= dim, parameter, text,
                      std::to_string(dim) + " expressions separated by ';'");
      parts.resize(dim);
      const auto f = parse_expressions<dim>(parts, parameter);
      return [f](const Point<dim> &x) {
        Tensor<1, dim> v;
        for (unsigned int d = 0; d < dim; ++d)
          v[d] = f->value(x, d);
        return v;
      };
    }

    // AMG for the PD stiffness K with the translations per component as the
    // near-null space (DoFs interleaved by component).
    template <int dim>
    void
    initialize_elasticity_amg(TrilinosWrappers::PreconditionAMG    &amg,
                              const TrilinosWrappers::SparseMatrix &K,
                              const IndexSet                       &owned)
    {
      TrilinosWrappers::PreconditionAMG::AdditionalData data;
      data.elliptic = true;
      data.constant_modes.assign(dim, std::vector<bool>(owned.n_elements(), false));
      for (unsigned int k = 0; k < owned.n_elements(); ++k)
        data.constant_modes[k % dim][k] = true;
      amg.initialize(K, data);
    }
  } // namespace

  template <int dim>
  void
  StaticMechanicsParameters<dim>::declare_parameters(ParameterHandler &prm)
  {
    prm.enter_subsection("Model");
    prm.enter_subsection("LPS");
    LPSModelParameters::declare_parameters(prm);
    prm.leave_subsection();
    prm.leave_subsection();

    prm.enter_subsection("Static mechanics");
    prm.declare_entry("Model", "LPS", Patterns::Selection("linearized bond-based|LPS"),
                      "Linearized bond-based (2.32), entries in Model/Bond-based (its "
                      "'Linearized' entry is implied), or linearized LPS (2.18)-(2.19), "
                      "entries in Model/LPS (2D: plane strain).");
    prm.declare_entry("Body force", "0; 0; 0", Patterns::Anything(),
                      "Body force density b, 'dim' expressions in x, y, z separated by ';'.");
    prm.declare_entry("Layer displacement", "0; 0; 0", Patterns::Anything(),
                      "Displacement prescribed on the volume-constraint layer "
                      "(Discretization/Volume constraint layer > 0).");
    prm.declare_entry("Prescribed displacements", "", Patterns::Anything(),
                      "Further node sets of the body with prescribed displacement: items "
                      "'LEVEL SET : UX; UY[; UZ]' separated by '|'; the set is "
                      "{LEVEL SET <= 0}; later items override earlier ones.");
    prm.declare_entry("Solver", "cg-amg", Patterns::Selection("cg-amg|direct"),
                      "CG with algebraic multigrid (Trilinos ML) or a direct solver (Amesos).");
    prm.declare_entry("Tolerance", "1e-10", Patterns::Double(),
                      "CG: relative residual reduction (0 < tol < 1).");
    prm.declare_entry("Max iterations", "10000", Patterns::Integer(1), "CG iteration limit.");
    prm.declare_entry("Quadrature", "standard", Patterns::Selection("standard|wls"),
                      "standard scheme, or the WLS collocation quadrature (Sect. 3.2, "
                      "(3.32)-(3.51)) on every free interior node (Model = LPS); the "
                      "non-symmetric system is then solved matrix-free with GMRES, "
                      "preconditioned by the Solver's factorization (AMG or direct) of "
                      "the standard-scheme stiffness.");
    prm.enter_subsection("WLS");
    WlsParameters::declare_parameters(prm);
    prm.leave_subsection();
    prm.leave_subsection();
  }

  template <int dim>
  void
  StaticMechanicsParameters<dim>::parse_parameters(ParameterHandler &p)
  {
    check_parameter(dim >= 2, "Dimension", dim, "2 or 3 for Problem = static mechanics");
    p.enter_subsection("Geometry");
    domain = Domain<dim>::create(p);
    p.leave_subsection();
    p.enter_subsection("Discretization");
    lattice.parse_parameters(p);
    p.leave_subsection();

    p.enter_subsection("Static mechanics");
    model = p.get("Model");
    body_force = vector_field<dim>(p.get("Body force"), "Static mechanics/Body force");
    layer_displacement =
      vector_field<dim>(p.get("Layer displacement"), "Static mechanics/Layer displacement");
    prescribed_displacements.clear();
    for (const auto &item : Utilities::split_string_list(p.get("Prescribed displacements"), '|'))
      {
        const std::string name  = "Static mechanics/Prescribed displacements";
        const auto        colon = item.find(':');
        check_parameter(colon != std::string::npos, name, item,
                        "items 'LEVEL SET : UX; UY[; UZ]' separated by '|'");
        const auto set = parse_expressions<dim>({item.substr(0, colon)}, name);
        prescribed_displacements.emplace_back(
          [set](const Point<dim> &x) { return set->value(x); },
          vector_field<dim>(item.substr(colon + 1), name));
      }
    solver         = p.get("Solver");
    tolerance      = p.get_double("Tolerance");
    max_iterations = p.get_integer("Max iterations");
    check_parameter(tolerance > 0. && tolerance < 1., "Static mechanics/Tolerance", tolerance,
                    "0 < tolerance < 1");
    quadrature = p.get("Quadrature");
    p.enter_subsection("WLS");
    wls.parse_parameters(p);
    p.leave_subsection();
    check_parameter(quadrature == "standard" || model == "LPS", "Static mechanics/Quadrature",
                    quadrature, "standard for Model = linearized bond-based (WLS: Model = LPS)");
    p.leave_subsection();

    p.enter_subsection("Model");
    p.enter_subsection("Bond-based");
    bond_based.parse_parameters(p);
    bond_based.linearized = true;
    p.leave_subsection();
    p.enter_subsection("LPS");
    lps.parse_parameters(p);
    p.leave_subsection();
    p.leave_subsection();
    // The static solve is linear: no bond breaking.
    if (model == "LPS")
      check_parameter(lps.critical_stretch == 0., "Model/LPS/Critical stretch",
                      lps.critical_stretch, "0 for Problem = static mechanics (linear solve)");
    if (model == "LPS")
      check_parameter(lps.fracture_energy == 0., "Model/LPS/Fracture energy", lps.fracture_energy,
                      "0 for Problem = static mechanics (linear solve)");
    else
      check_parameter(bond_based.critical_stretch == 0. && bond_based.fracture_energy == 0.,
                      "Model/Bond-based/Critical stretch, Fracture energy",
                      bond_based.critical_stretch + bond_based.fracture_energy,
                      "0 for Problem = static mechanics (linear solve)");

    p.enter_subsection("Output");
    output_directory = p.get("Directory");
    p.leave_subsection();
  }

  template <int dim>
  StaticMechanicsSolver<dim>::StaticMechanicsSolver(const MPI_Comm                        comm,
                                                    const StaticMechanicsParameters<dim> &p)
    : mpi_communicator(comm)
    , prm(p)
    , disc(comm)
  {
    check_parameter(prm.model == "LPS" || prm.model == "linearized bond-based",
                    "Static mechanics/Model", prm.model, "linearized bond-based|LPS");
    check_parameter(prm.solver == "cg-amg" || prm.solver == "direct", "Static mechanics/Solver",
                    prm.solver, "cg-amg|direct");
  }

  template <int dim>
  void
  StaticMechanicsSolver<dim>::setup()
  {
    AssertThrow(prm.domain, ExcMessage("StaticMechanicsParameters: no domain"));
    disc.setup(*prm.domain, prm.lattice);
    if (prm.model == "LPS")
      lps = std::make_unique<LinearizedLPSOperator<dim>>(disc, prm.lps);
    else
      {
        auto bb       = prm.bond_based;
        bb.linearized = true;
        bond_based    = std::make_unique<BondBasedOperator<dim>>(disc, bb);
      }

    // Prescribed nodes: the layer, then the node sets (later ones win).
    const unsigned int n = disc.n_owned() + disc.n_ghost();
    fixed.assign(n, 0);
    prescribed.assign(n, Tensor<1, dim>());
    for (unsigned int i = 0; i < n; ++i)
      {
        const Point<dim> &x = disc.position[i];
        if (disc.region[i] == Discretization<dim>::constrained && prm.layer_displacement)
          {
            fixed[i]      = 1;
            prescribed[i] = prm.layer_displacement(x);
          }
        for (const auto &set : prm.prescribed_displacements)
          if (set.first(x) <= 0.)
            {
              fixed[i]      = 1;
              prescribed[i] = set.second(x);
            }
      }
    std::uint64_t n_fixed = 0;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      n_fixed += fixed[i];
    check_parameter(Utilities::MPI::sum(n_fixed, mpi_communicator) > 0,
                    "Discretization/Volume constraint layer, Static mechanics/Prescribed "
                    "displacements",
                    "no prescribed node",
                    "a constraint layer or node set that removes the rigid-body modes");
    for (auto &c : u)
      disc.initialize_vector(c);

    check_parameter(prm.quadrature == "standard" || (prm.quadrature == "wls" && lps),
                    "Static mechanics/Quadrature", prm.quadrature,
                    "standard, or wls with Model = LPS");
    if (prm.quadrature == "wls")
      {
        std::vector<unsigned int> rows;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (disc.region[i] == Discretization<dim>::interior && !fixed[i])
            rows.push_back(i);
        lps->set_wls_rows(prm.wls, rows);
      }
  }

  template <int dim>
  void
  StaticMechanicsSolver<dim>::compute_forces(const VectorField &v, VectorField &f)
  {
    if (lps)
      lps->compute_forces(v, f);
    else
      bond_based->compute_forces(v, f);
  }

  template <int dim>
  void
  StaticMechanicsSolver<dim>::assemble(TrilinosWrappers::SparseMatrix   &matrix,
                                       const std::vector<unsigned char> &fixed_mask) const
  {
    if (lps)
      Stiffness::assemble(*lps, matrix, fixed_mask);
    else
      Stiffness::assemble(*bond_based, matrix, fixed_mask);
  }

  template <int dim>
  void
  StaticMechanicsSolver<dim>::assemble_by_probing(TrilinosWrappers::SparseMatrix &matrix)
  {
    // The WLS force is linear in u but has no bond structure to assemble
    // from, so its matrix is recovered column by column from compute_forces():
    // the force of row i depends on u within the two-hop reach R = 2 (delta
    // + dx/2) (the fit of i reads its collocation nodes' dilatations, each a
    // fit over that node's family). Nodes whose lattice coordinates agree
    // modulo P = 2 R/dx + 1 (rounded up) are at least 2 R + dx apart, so the
    // rows reached by two probed nodes of one colour never overlap: one
    // evaluation per colour and component gives all those columns. Rows and
    // columns of prescribed nodes are removed, their diagonal is 1 (as
    // Stiffness::assemble).
    const double    dx    = prm.lattice.dx;
    const long long reach = (long long)std::ceil(2. * (prm.lattice.delta + 0.5 * dx) / dx - 1e-9);
    const long long P     = 2 * reach + 1;
    const unsigned int n_local = disc.n_owned() + disc.n_ghost();
    // integer lattice coordinates relative to the global lowest node
    Point<dim> lo;
    for (unsigned int d = 0; d < dim; ++d)
      {
        double l = std::numeric_limits<double>::max();
        for (unsigned int i = 0; i < n_local; ++i)
          l = std::min(l, disc.position[i][d]);
        lo[d] = Utilities::MPI::min(l, mpi_communicator);
      }
    std::vector<std::array<long long, dim>> coord(n_local);
    for (unsigned int i = 0; i < n_local; ++i)
      for (unsigned int d = 0; d < dim; ++d)
        coord[i][d] = std::llround((disc.position[i][d] - lo[d]) / dx);
    auto key = [](const std::array<long long, dim> &c) {
      long long k = 0;
      for (unsigned int d = 0; d < dim; ++d)
        k = k * (1LL << 20) + c[d];
      return k;
    };
    // lattice key -> global node index of every node (the two-hop reach
    // exceeds the ghost layer); small static problems only
    std::vector<long long> mine;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      mine.insert(mine.end(),
                  {key(coord[i]), (long long)disc.partitioner()->local_to_global(i)});
    std::map<long long, types::global_dof_index> global_of;
    for (const auto &v : Utilities::MPI::all_gather(mpi_communicator, mine))
      for (std::size_t q = 0; q < v.size(); q += 2)
        global_of[v[q]] = v[q + 1];
    std::vector<char> fixed_global(disc.n_global(), 0);
    {
      std::vector<types::global_dof_index> f;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (fixed[i])
          f.push_back(disc.partitioner()->local_to_global(i));
      for (const auto &v : Utilities::MPI::all_gather(mpi_communicator, f))
        for (const auto g : v)
          fixed_global[g] = 1;
    }

    VectorField probe, force;
    for (unsigned int d = 0; d < dim; ++d)
      {
        disc.initialize_vector(probe[d]);
        disc.initialize_vector(force[d]);
      }
    const types::global_dof_index              first = disc.partitioner()->local_range().first;
    std::vector<std::map<types::global_dof_index, double>> rows(dim * disc.n_owned());
    long long n_colours = 1;
    for (unsigned int d = 0; d < dim; ++d)
      n_colours *= P;
    for (long long colour = 0; colour < n_colours; ++colour)
      {
        std::array<long long, dim> cc;
        for (long long rest = colour, d = 0; d < dim; ++d, rest /= P)
          cc[d] = rest % P;
        auto has_colour = [&](const std::array<long long, dim> &c) {
          for (unsigned int d = 0; d < dim; ++d)
            if (c[d] % P != cc[d])
              return false;
          return true;
        };
        for (unsigned int comp = 0; comp < dim; ++comp)
          {
            for (unsigned int d = 0; d < dim; ++d)
              for (unsigned int i = 0; i < n_local; ++i)
                probe[d].local_element(i) =
                  d == comp && !fixed[i] && has_colour(coord[i]) ? 1. : 0.;
            compute_forces(probe, force);
            for (unsigned int i = 0; i < disc.n_owned(); ++i)
              {
                if (fixed[i])
                  continue;
                // the one node of this colour within the reach of row i
                std::array<long long, dim> s;
                bool                       inside = true;
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    s[d] = coord[i][d] - reach + ((cc[d] - (coord[i][d] - reach)) % P + P) % P;
                    inside = inside && s[d] <= coord[i][d] + reach && s[d] >= 0;
                  }
                const auto it = inside ? global_of.find(key(s)) : global_of.end();
                for (unsigned int a = 0; a < dim; ++a)
                  {
                    const double v = force[a].local_element(i);
                    if (v == 0.)
                      continue;
                    AssertThrow(it != global_of.end() && !fixed_global[it->second],
                                ExcMessage("WLS stiffness by probing: a force beyond the "
                                           "two-hop reach of the probed node"));
                    rows[dim * i + a][dim * it->second + comp] = -v;
                  }
              }
          }
      }
    // prescribed rows: identity
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (fixed[i])
        for (unsigned int a = 0; a < dim; ++a)
          rows[dim * i + a][dim * (first + i) + a] = 1.;

    const IndexSet                     owned = Stiffness::owned_dofs(disc);
    TrilinosWrappers::SparsityPattern sp(owned, owned, mpi_communicator);
    for (unsigned int r = 0; r < rows.size(); ++r)
      for (const auto &[c, v] : rows[r])
        sp.add(dim * first + r, c);
    sp.compress();
    matrix.reinit(sp);
    for (unsigned int r = 0; r < rows.size(); ++r)
      for (const auto &[c, v] : rows[r])
        matrix.set(dim * first + r, c, v);
    matrix.compress(VectorOperation::insert);
  }

  template <int dim>
  void
  StaticMechanicsSolver<dim>::solve()
  {
    Timer                          timer;
    TrilinosWrappers::SparseMatrix K;
    assemble(K, fixed);

    // u_C: prescribed values on fixed nodes, 0 elsewhere; f(u_C) = -K u_C.
    VectorField uc, f, rhs_field;
    for (unsigned int d = 0; d < dim; ++d)
      {
        disc.initialize_vector(uc[d]);
        disc.initialize_vector(f[d]);
        disc.initialize_vector(rhs_field[d]);
      }
    for (unsigned int i = 0; i < disc.n_owned() + disc.n_ghost(); ++i)
      if (fixed[i])
        for (unsigned int d = 0; d < dim; ++d)
          uc[d].local_element(i) = prescribed[i][d];
    compute_forces(uc, f);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const Tensor<1, dim> b = fixed[i] ? prescribed[i] : prm.body_force(disc.position[i]);
        for (unsigned int d = 0; d < dim; ++d)
          rhs_field[d].local_element(i) = fixed[i] ? b[d] : b[d] + f[d].local_element(i);
      }

    const IndexSet                owned = Stiffness::owned_dofs(disc);
    TrilinosWrappers::MPI::Vector rhs(owned, mpi_communicator), x(rhs), res(rhs);
    Stiffness::to_dofs(disc, rhs_field, rhs);
    // Initial guess: the prescribed values (exact on the fixed rows).
    Stiffness::to_dofs(disc, uc, x);

    SolverControl control(prm.max_iterations, prm.tolerance * rhs.l2_norm());
    if (lps && lps->wls_quadrature() && prm.solver == "direct")
      {
        // The WLS stiffness is non-symmetric and, for high orders on fine
        // lattices (WLS-4 at m >= 6), its collocation misses the
        // grid-scale modes that dominate the standard K: K_std^{-1} K_wls
        // then has eigenvalues near 0 and GMRES preconditioned with K_std
        // stalls (WLS-4, m = 6, 8: no convergence in 10000 iterations;
        // m = 4: 6293). The direct factorization of the assembled K_wls has
        // no such dependence on the spectrum.
        assemble_by_probing(K);
      }
    else if (lps && lps->wls_quadrature())
      {
        // Matrix-free K x: fixed rows identity, fixed columns dropped, the
        // free rows -f(x with the fixed entries zeroed); GMRES with the AMG
        // of the standard-scheme stiffness K (same continuum operator) as a
        // right preconditioner, so that the stopping test is on the true
        // residual ||b - K_wls x|| <= tolerance ||b|| (left preconditioning
        // would test ||P^{-1} (b - K_wls x)||, a displacement-scaled norm
        // that the force-scaled tolerance does not fit).
        VectorField xf, fx;
        for (unsigned int d = 0; d < dim; ++d)
          {
            disc.initialize_vector(xf[d]);
            disc.initialize_vector(fx[d]);
          }
        struct WlsSystem
        {
          std::function<void(TrilinosWrappers::MPI::Vector &, const TrilinosWrappers::MPI::Vector &)>
            apply;
          void
          vmult(TrilinosWrappers::MPI::Vector &dst, const TrilinosWrappers::MPI::Vector &src) const
          {
            apply(dst, src);
          }
        } system;
        system.apply = [&](TrilinosWrappers::MPI::Vector       &dst,
                           const TrilinosWrappers::MPI::Vector &src) {
          Stiffness::from_dofs(disc, src, xf);
          for (unsigned int i = 0; i < disc.n_owned() + disc.n_ghost(); ++i)
            if (fixed[i])
              for (unsigned int d = 0; d < dim; ++d)
                xf[d].local_element(i) = 0.;
          compute_forces(xf, fx);
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            for (unsigned int d = 0; d < dim; ++d)
              fx[d].local_element(i) =
                fixed[i] ? src[dim * types::global_dof_index(disc.partitioner()->local_to_global(i)) + d] :
                           -fx[d].local_element(i);
          Stiffness::to_dofs(disc, fx, dst);
        };
        SolverGMRES<TrilinosWrappers::MPI::Vector>::AdditionalData gmres_data(300, true);
        SolverGMRES<TrilinosWrappers::MPI::Vector> gmres(control, gmres_data);
        TrilinosWrappers::PreconditionAMG amg;
        initialize_elasticity_amg<dim>(amg, K, owned);
        gmres.solve(system, x, rhs, amg);
        iterations = control.last_step();
        system.vmult(res, x);
        res -= rhs;
        residual = res.l2_norm() / std::max(rhs.l2_norm(), std::numeric_limits<double>::min());
        Stiffness::from_dofs(disc, x, u);
        solve_seconds = timer.wall_time();
        return;
      }
    if (prm.solver == "direct")
      {
        TrilinosWrappers::SolverDirect direct(control);
        direct.solve(K, x, rhs);
        iterations = 1;
      }
    else
      {
        TrilinosWrappers::PreconditionAMG amg;
        initialize_elasticity_amg<dim>(amg, K, owned);
        TrilinosWrappers::SolverCG cg(control);
        cg.solve(K, x, rhs, amg);
        iterations = control.last_step();
      }
    K.vmult(res, x);
    res -= rhs;
    residual = res.l2_norm() / std::max(rhs.l2_norm(), std::numeric_limits<double>::min());
    Stiffness::from_dofs(disc, x, u);
    solve_seconds = timer.wall_time();
  }

  template <int dim>
  double
  StaticMechanicsSolver<dim>::strain_energy() const
  {
    return lps ? lps->total_strain_energy(u) : bond_based->total_strain_energy(u);
  }

  template <int dim>
  Tensor<1, dim>
  StaticMechanicsSolver<dim>::reaction_force()
  {
    VectorField f;
    for (auto &c : f)
      disc.initialize_vector(c);
    compute_forces(u, f);
    Tensor<1, dim> r;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (fixed[i])
        for (unsigned int d = 0; d < dim; ++d)
          r[d] -= f[d].local_element(i) * disc.volume[i];
    return Utilities::MPI::sum(r, mpi_communicator);
  }

  template <int dim>
  Tensor<1, dim>
  StaticMechanicsSolver<dim>::total_body_force() const
  {
    Tensor<1, dim> s;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (!fixed[i])
        s += prm.body_force(disc.position[i]) * disc.volume[i];
    return Utilities::MPI::sum(s, mpi_communicator);
  }

  template <int dim>
  void
  StaticMechanicsSolver<dim>::output()
  {
    if (prm.output_directory.empty())
      return;
    Vector magnitude;
    disc.initialize_vector(magnitude);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        double s = 0.;
        for (unsigned int d = 0; d < dim; ++d)
          s += u[d].local_element(i) * u[d].local_element(i);
        magnitude.local_element(i) = std::sqrt(s);
      }
    std::vector<std::pair<std::string, const Vector *>> fields;
    const char *names[3] = {"u_x", "u_y", "u_z"};
    for (unsigned int d = 0; d < dim; ++d)
      fields.emplace_back(names[d], &u[d]);
    fields.emplace_back("u_magnitude", &magnitude);
    NodeOutput<dim> vtu(disc, prm.output_directory, "solution");
    vtu.write(0., 0, fields);

    // Collective quantities on every rank, written by rank 0.
    const double  energy   = strain_energy();
    const auto    reaction = reaction_force();
    const auto    body     = total_body_force();
    const auto    n_bonds  = disc.n_global_bonds();
    if (Utilities::MPI::this_mpi_process(mpi_communicator) == 0)
      {
        std::ofstream out(prm.output_directory + "/summary.txt");
        out << std::setprecision(12);
        out << "model: " << prm.model << "\ndimension: " << dim
            << "\nnodes: " << disc.n_global() << "\nbonds: " << n_bonds
            << "\nsolver: " << prm.solver << "\niterations: " << iterations
            << "\nrelative_residual: " << residual << "\nsolve_seconds: " << solve_seconds
            << "\nstrain_energy: " << energy;
        for (unsigned int d = 0; d < dim; ++d)
          out << "\nreaction_force_" << names[d] + 2 << ": " << reaction[d];
        for (unsigned int d = 0; d < dim; ++d)
          out << "\nbody_force_" << names[d] + 2 << ": " << body[d];
        out << "\n";
      }
  }

  template <int dim>
  void
  run_static_mechanics(ParameterHandler &prm, const MPI_Comm comm)
  {
    if constexpr (dim == 1)
      {
        (void)prm;
        (void)comm;
        throw ParameterError("Dimension", "1", "2 or 3 for Problem = static mechanics");
      }
    else
      {
        StaticMechanicsParameters<dim> parameters;
        parameters.parse_parameters(prm);
        StaticMechanicsSolver<dim> solver(comm, parameters);
        solver.setup();
        solver.solve();
        solver.output();
        const double energy   = solver.strain_energy();
        const auto   reaction = solver.reaction_force();
        if (Utilities::MPI::this_mpi_process(comm) == 0)
          std::cout << "Static " << parameters.model << " in " << dim << "D: "
                    << solver.discretization().n_global() << " nodes, "
                    << solver.n_iterations() << " iterations, relative residual "
                    << solver.relative_residual() << ", strain energy " << energy
                    << ", reaction force " << reaction << std::endl;
      }
  }

  template void run_static_mechanics<1>(ParameterHandler &, const MPI_Comm);
  template void run_static_mechanics<2>(ParameterHandler &, const MPI_Comm);
  template void run_static_mechanics<3>(ParameterHandler &, const MPI_Comm);
  template struct StaticMechanicsParameters<1>;
  template struct StaticMechanicsParameters<2>;
  template struct StaticMechanicsParameters<3>;
  template class StaticMechanicsSolver<2>;
  template class StaticMechanicsSolver<3>;
} // namespace PeriDEAL
