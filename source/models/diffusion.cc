#include <deal.II/lac/trilinos_sparsity_pattern.h>

#include <perideal/base/exceptions.h>
#include <perideal/models/diffusion.h>

#include <algorithm>
#include <cmath>

namespace PeriDEAL
{
  namespace
  {
#if defined(__GNUC__) && !defined(__clang__)
#  define PERIDEAL_SCALAR_LOOP __attribute__((optimize("no-tree-vectorize")))
#else
#  define PERIDEAL_SCALAR_LOOP
#endif
    // Short rows: scalar loads and four independent FMA chains. On this
    // hardware AVX-512 gathers plus the per-row vector reduction cost more
    // than they save below ~1000 bonds per row (doc/benchmarks.md: 1.74x
    // on 2D m = 3).
    PERIDEAL_SCALAR_LOOP inline double
    weighted_row_sum_short(const std::int32_t *ci,
                           const double       *wi,
                           const unsigned int  m,
                           const double       *c)
    {
      double       s0 = 0., s1 = 0., s2 = 0., s3 = 0.;
      unsigned int k  = 0;
      for (; k + 4 <= m; k += 4)
        {
          s0 += wi[k] * c[ci[k]];
          s1 += wi[k + 1] * c[ci[k + 1]];
          s2 += wi[k + 2] * c[ci[k + 2]];
          s3 += wi[k + 3] * c[ci[k + 3]];
        }
      for (; k < m; ++k)
        s0 += wi[k] * c[ci[k]];
      return (s0 + s1) + (s2 + s3);
    }

    // Long rows (3D, large m): the vectorized gather loop wins.
    inline double
    weighted_row_sum_long(const std::int32_t *ci,
                          const double       *wi,
                          const unsigned int  m,
                          const double       *c)
    {
      double s = 0.;
#pragma omp simd reduction(+ : s)
      for (unsigned int k = 0; k < m; ++k)
        s += wi[k] * c[ci[k]];
      return s;
    }

    // One row of linear diffusion, kappa (sum_j w_ij c_j - (sum_j w_ij) c_i).
    inline double
    linear_row(const std::int32_t *ci,
               const double       *wi,
               const unsigned int  m,
               const double       *c,
               const double        row_sum,
               const double        c_i,
               const double        kappa)
    {
      const double s = m < 1024 ? weighted_row_sum_short(ci, wi, m, c) :
                                  weighted_row_sum_long(ci, wi, m, c);
      return kappa * (s - row_sum * c_i);
    }

    // i -> (L C)_i of linear diffusion's standard row i, raw pointers taken
    // once outside the row loops (both DiffusionOperator::apply()s).
    template <typename Table>
    auto
    linear_rows(const Table                &nb,
                const std::vector<double> &geometric_weight,
                const std::vector<double> &row_sum,
                const double               kappa,
                const Vector              &C)
    {
      const double *const  c         = C.begin();
      const std::int32_t  *col       = nb.col.data();
      const std::uint64_t *row_start = nb.row_start.data();
      const std::uint64_t *table     = nb.table_start.data();
      const double        *gw        = geometric_weight.data();
      const double        *rs        = row_sum.data();
      return [=](const unsigned int i) {
        return linear_row(col + row_start[i], gw + table[i], row_start[i + 1] - row_start[i], c,
                          rs[i], c[i], kappa);
      };
    }
  } // namespace

  void
  DiffusionModelParameters::declare_parameters(ParameterHandler &prm)
  {
    prm.declare_entry("Type", "diffusion", Patterns::Selection("diffusion|corrosion"),
                      "diffusion: linear PD diffusion (2.41)-(2.42). corrosion: the "
                      "bi-material corrosion model (2.48)-(2.49) with phase change "
                      "(2.79): liquid-liquid bonds use the liquid micro-diffusivity, "
                      "solid-liquid bonds the interface one, solid-solid bonds the "
                      "solid one (default 0: no flux).");
    prm.declare_entry("Influence function", "constant", Patterns::Selection("constant|linear"),
                      "omega_0 = 1 (2.12) or omega_1 = 1 - r/delta (2.13).");
    prm.declare_entry("Kernel exponent", "2", Patterns::Double(),
                      "q: the kernel is kappa omega Theta / |xi|^q (convention J_q of "
                      "(2.42)) or / |xi|^(n_d + 2q) (convention of (2.49)).");
    prm.declare_entry("Kernel convention", "J_q", Patterns::Selection("J_q|n_d+2q"),
                      "Which exponent the kernel uses, see 'Kernel exponent'.");
    prm.declare_entry("Diffusivity", "1", Patterns::Double(),
                      "Local diffusion coefficient D (> 0); kappa is computed from it "
                      "by quadrature of the kernel (Table 4.1) unless "
                      "'Micro-diffusivity' is positive.");
    prm.declare_entry("Micro-diffusivity", "0", Patterns::Double(),
                      "kappa of linear diffusion, used as given if > 0.");
    prm.enter_subsection("Corrosion");
    prm.declare_entry("Liquid micro-diffusivity", "2", Patterns::Double(),
                      "kappa_liq of liquid-liquid bonds (>= 0).");
    prm.declare_entry("Interface micro-diffusivity", "0.1", Patterns::Double(),
                      "kappa_int of solid-liquid bonds (>= 0).");
    prm.declare_entry("Solid micro-diffusivity", "0", Patterns::Double(),
                      "kappa of solid-solid bonds (>= 0); 0 in the sources.");
    prm.declare_entry("Saturation concentration", "0.85", Patterns::Double(),
                      "C_sat of (2.79): a solid node becomes liquid once its "
                      "concentration falls below it, and never turns back.");
    prm.declare_entry("Phase rule", "one-way", Patterns::Selection("one-way|concentration"),
                      "one-way: (2.79), solid to liquid only. concentration: the phase "
                      "follows the current concentration (paper 003, eq. 6): solid "
                      "(above the phase-change concentration = 'Saturation "
                      "concentration') whenever C >= C_sat, liquid otherwise.");
    prm.leave_subsection();
  }

  void
  DiffusionModelParameters::parse_parameters(ParameterHandler &prm, const unsigned int dim)
  {
    type  = prm.get("Type");
    omega = parse_influence_function(prm.get("Influence function"), "Model/Influence function");
    const double q = prm.get_double("Kernel exponent");
    exponent       = prm.get("Kernel convention") == "J_q" ? q : dim + 2. * q;
    // The second moment exists only for 2 - exponent + dim - 1 > -1.
    check_parameter(exponent < dim + 2., "Model/Kernel exponent", q,
                    "a value for which the kernel has a finite second moment "
                    "(exponent of |xi| < n_d + 2, i.e. q < " +
                      std::to_string(prm.get("Kernel convention") == "J_q" ? dim + 2 : 1) + ")");
    diffusivity       = prm.get_double("Diffusivity");
    micro_diffusivity = prm.get_double("Micro-diffusivity");
    check_parameter(micro_diffusivity >= 0., "Model/Micro-diffusivity", micro_diffusivity,
                    "a non-negative number (0: compute from Diffusivity)");
    if (micro_diffusivity == 0.)
      check_parameter(diffusivity > 0., "Model/Diffusivity", diffusivity, "a positive number");
    prm.enter_subsection("Corrosion");
    kappa_liquid    = prm.get_double("Liquid micro-diffusivity");
    kappa_interface = prm.get_double("Interface micro-diffusivity");
    kappa_solid     = prm.get_double("Solid micro-diffusivity");
    saturation      = prm.get_double("Saturation concentration");
    reversible_phase = prm.get("Phase rule") == "concentration";
    prm.leave_subsection();
    check_parameter(kappa_liquid >= 0., "Model/Corrosion/Liquid micro-diffusivity",
                    kappa_liquid, "a non-negative number");
    check_parameter(kappa_interface >= 0., "Model/Corrosion/Interface micro-diffusivity",
                    kappa_interface, "a non-negative number");
    check_parameter(kappa_solid >= 0., "Model/Corrosion/Solid micro-diffusivity",
                    kappa_solid, "a non-negative number");
  }

  bool
  update_corrosion_phase(const DiffusionModelParameters &p,
                         const Vector                   &C,
                         Vector                         &phase,
                         const unsigned int              n_owned)
  {
    bool changed = false;
    for (unsigned int i = 0; i < n_owned; ++i)
      {
        const bool solid = phase.local_element(i) > 0.5;
        // one-way (2.79): solid -> liquid below C_sat; 003 (6): both ways
        const bool to_liquid = solid && C.local_element(i) < p.saturation;
        const bool to_solid  = p.reversible_phase && !solid && C.local_element(i) >= p.saturation;
        if (to_liquid || to_solid)
          {
            phase.local_element(i) = to_solid ? 1. : 0.;
            changed                = true;
          }
      }
    return changed;
  }

  template <int dim>
  DiffusionOperator<dim>::DiffusionOperator(const Discretization<dim>      &discretization,
                                            const DiffusionModelParameters &p)
    : disc(discretization)
    , corrosion(p.type == "corrosion")
  {
    scalar_kernel.dim      = dim;
    scalar_kernel.omega    = p.omega;
    scalar_kernel.exponent = p.exponent;
    scalar_kernel.delta    = disc.parameters().delta;
    scalar_kernel.constant = 1.;
    if (corrosion)
      kappa_table = {{p.kappa_liquid, p.kappa_interface, p.kappa_interface, p.kappa_solid}};
    else
      {
        const double kappa = p.micro_diffusivity > 0. ?
                               p.micro_diffusivity :
                               scalar_kernel.micro_constant_for(p.diffusivity);
        scalar_kernel.constant = kappa;
        kappa_table            = {{kappa, kappa, kappa, kappa}};
      }

    const auto &nb = disc.neighborhood;
    geometric_weight.resize(nb.bond_length.size());
    ScalarKernel shape = scalar_kernel;
    shape.constant     = 1.;
    // omega is evaluated at min(r, delta): bonds of the partial-volume shell
    // beyond delta keep the kernel's value at the horizon, weighted by beta.
    for (std::size_t t = 0; t < geometric_weight.size(); ++t)
      geometric_weight[t] =
        shape(std::min(nb.bond_length[t], shape.delta)) * nb.bond_weight[t];

    row_sum.resize(disc.n_owned());
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const double *w = geometric_weight.data() + nb.table_start[i];
        double        s = 0.;
        for (std::uint64_t k = 0; k < nb.row_start[i + 1] - nb.row_start[i]; ++k)
          s += w[k];
        row_sum[i] = s;
      }
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (disc.region[i] == Discretization<dim>::interior)
        interior_standard_rows.push_back(i);
  }

  template <int dim>
  void
  DiffusionOperator<dim>::apply(const Vector &C, Vector &rate, const Vector *phase) const
  {
    apply(C, rate, phase, Rows::all);
  }

  template <int dim>
  void
  DiffusionOperator<dim>::apply(const Vector &C,
                                Vector       &rate,
                                const Vector *phase,
                                const Rows    rows) const
  {
    const auto          &nb        = disc.neighborhood;
    const double *const  c         = C.begin();
    double *const        r         = rate.begin();
    const std::int32_t  *col       = nb.col.data();
    const std::uint64_t *row_start = nb.row_start.data();
    const std::uint64_t *table     = nb.table_start.data();
    const double        *gw        = geometric_weight.data();
    const unsigned int   n         = disc.n_owned();
    // The standard-scheme rows: all owned rows except Omega_w (written by
    // the WLS rows below), or the list of interior ones built at setup.
    const unsigned char *skip = is_wls.empty() ? nullptr : is_wls.data();
    auto for_standard_rows    = [&](auto &&row) {
      if (rows == Rows::interior)
        for (const unsigned int i : interior_standard_rows)
          row(i);
      else
        for (unsigned int i = 0; i < n; ++i)
          if (skip == nullptr || !skip[i])
            row(i);
    };

    if (!corrosion)
      {
        const auto row = linear_rows(disc.neighborhood, geometric_weight, row_sum, kappa_table[0], C);
        for_standard_rows([&](const unsigned int i) { r[i] = row(i); });
        if (wls) // Omega_w: the WLS rows (weights carry kappa), same short-row kernel
          for (unsigned int k = 0; k < wls->node.size(); ++k)
            {
              const auto b = wls->row_start[k];
              r[wls->node[k]] = weighted_row_sum_short(wls->col.data() + b, wls->weight.data() + b,
                                                       wls->row_start[k + 1] - b, c);
            }
        return;
      }

    AssertThrow(phase != nullptr, ExcMessage("The corrosion model needs the phase field."));
    const double *const ph           = phase->begin();
    auto                standard_row = [&](const unsigned int i) {
      const std::int32_t *ci    = col + row_start[i];
      const double       *wi    = gw + table[i];
      const unsigned int  m     = row_start[i + 1] - row_start[i];
      const double       *kappa = kappa_table.data() + (ph[i] > 0.5 ? 2 : 0);
      const double        c_i   = c[i];
      double              s     = 0.;
      for (unsigned int k = 0; k < m; ++k)
        {
          const std::int32_t j = ci[k];
          s += wi[k] * kappa[ph[j] > 0.5] * (c[j] - c_i);
        }
      return s;
    };
    // Rows whose neighbours are all of one phase: one kappa on every bond,
    // the same products as standard_row() without the phase look-ups, in
    // four chains (equal up to round-off). kappa = 0 (solid interior): every
    // term of standard_row() is a signed zero and its sum +0, so the row is
    // exactly 0 without summing.
    const unsigned int n_local = n + disc.n_ghost();
    if (classify)
      {
        auto solid = [&](const unsigned int j) { return ph[j] > 0.5; };
        if (!solid_count.initialized())
          solid_count.initialize(n, row_start, col, n_local, solid);
        else
          solid_count.update(solid);
      }
    auto row_value = [&](const unsigned int i) {
      const int uniform = classify ? solid_count.uniform_phase(i) : -1;
      if (uniform < 0)
        {
          if (!classify)
            return standard_row(i);
          // both phases: kappa per bond from the neighbour's phase flag (a
          // byte gather), the products of standard_row() in four chains
          const double        *kappa = kappa_table.data() + (ph[i] > 0.5 ? 2 : 0);
          const unsigned char *solid = solid_count.solid_flags();
          return PeriDEAL::internal::phase_row_sum(col + row_start[i], gw + table[i],
                                         row_start[i + 1] - row_start[i], c, c[i],
                                         [&](const std::int32_t j) { return kappa[solid[j]]; });
        }
      const double kappa = bond_kappa(ph[i] > 0.5, uniform == 1);
      if (kappa == 0.)
        return 0.;
      // one kappa: four chains (round-off differences from the per-bond loop)
      return PeriDEAL::internal::phase_row_sum(col + row_start[i], gw + table[i],
                                     row_start[i + 1] - row_start[i], c, c[i],
                                     [kappa](std::int32_t) { return kappa; });
    };
    for_standard_rows([&](const unsigned int i) { r[i] = row_value(i); });
    if (wls)
      // Omega_w: a WLS row is one phase's operator, valid while all its
      // collocation nodes share the phase of x_i (kappa of that phase's
      // bonds, the weights carry no kappa); once the interface reaches them
      // the row falls back to the standard scheme. The collocation nodes
      // are family nodes (or x_i): a family of x_i's phase needs no check.
      for (unsigned int k = 0; k < wls->node.size(); ++k)
        {
          const unsigned int i     = wls->node[k];
          const bool         solid = ph[i] > 0.5;
          const auto         b = wls->row_start[k], e = wls->row_start[k + 1];
          bool same = classify && solid_count.uniform_phase(i) == int(solid);
          if (!same)
            {
              same = true;
              for (auto t = b; t < e && same; ++t)
                same = (ph[wls->col[t]] > 0.5) == solid;
            }
          r[i] = same ? bond_kappa(solid, solid) *
                          weighted_row_sum_short(wls->col.data() + b, wls->weight.data() + b,
                                                 e - b, c) :
                        row_value(i);
        }
  }

  template <int dim>
  void
  DiffusionOperator<dim>::apply(const Vector                                   &C,
                                Vector                                         &rate,
                                const std::vector<std::array<unsigned int, 2>> &rows) const
  {
    AssertThrow(!corrosion && !wls,
                ExcMessage("apply() on row ranges: linear diffusion without WLS rows only"));
    double *const r   = rate.begin();
    const auto    row = linear_rows(disc.neighborhood, geometric_weight, row_sum, kappa_table[0], C);
    for (const auto &range : rows)
      for (unsigned int i = range[0]; i < range[1]; ++i)
        r[i] = row(i);
  }

  template <int dim>
  double
  DiffusionOperator<dim>::critical_time_step() const
  {
    // Row-wise Gershgorin bound of the forward Euler iteration matrix
    // I + dt L restricted to the unknowns: values on the volume-constraint
    // layer are prescribed (they carry no error), so their couplings count
    // in the diagonal |l_ii| but not in the disc radius R_i. The disc lies in
    // [-1, 1] iff dt <= 2/(|l_ii| + R_i) (R_i <= |l_ii| always holds here).
    // In the bulk R_i = |l_ii| and this is (16) of 003 with beta; with
    // homogeneous Neumann ends (no layer) every row is of that kind.
    const double kappa_max = *std::max_element(kappa_table.begin(), kappa_table.end());
    const auto  &nb        = disc.neighborhood;
    double       max_sum   = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      // (corrosion: WLS rows may fall back to the standard row, so both count)
      if (disc.region[i] == Discretization<dim>::interior &&
          (is_wls.empty() || !is_wls[i] || corrosion))
        {
          const double *w      = geometric_weight.data() + nb.table_start[i];
          double        radius = 0.;
          for (std::uint64_t k = nb.row_start[i]; k < nb.row_start[i + 1]; ++k)
            if (disc.region[nb.col[k]] == Discretization<dim>::interior)
              radius += w[k - nb.row_start[i]];
          max_sum = std::max(max_sum, 0.5 * kappa_max * (row_sum[i] + radius));
        }
    // WLS rows: the same bound with the actual weights (some negative).
    if (wls)
      for (unsigned int k = 0; k < wls->node.size(); ++k)
        max_sum = std::max(max_sum, 0.5 * (corrosion ? kappa_max : 1.) * wls_gershgorin(k).first);
    max_sum = Utilities::MPI::max(max_sum, disc.get_mpi_communicator());
    return max_sum > 0. ? 1. / max_sum : std::numeric_limits<double>::infinity();
  }

  template <int dim>
  void
  DiffusionOperator<dim>::set_wls_rows(const WlsParameters             &parameters,
                                       const std::vector<unsigned int> &rows)
  {
    is_wls.assign(disc.n_owned(), 0);
    for (const unsigned int i : rows)
      {
        AssertThrow(i < disc.n_owned() && disc.region[i] == Discretization<dim>::interior,
                    ExcMessage("WLS rows must be owned interior nodes."));
        is_wls[i] = 1;
      }
    interior_standard_rows.erase(std::remove_if(interior_standard_rows.begin(),
                                                interior_standard_rows.end(),
                                                [&](const unsigned int i) { return is_wls[i]; }),
                                 interior_standard_rows.end());
    // Diffusion: the kernel carries kappa; corrosion: constant 1, kappa per row.
    wls = std::make_unique<WlsQuadrature<dim>>(parameters, scalar_kernel);
    // Not build(disc, rows): an empty list would mean "all interior nodes".
    wls->build(disc.position, disc.neighborhood.row_start, disc.neighborhood.col, rows);
  }

  template <int dim>
  std::pair<double, bool>
  DiffusionOperator<dim>::wls_gershgorin(const unsigned int k) const
  {
    const unsigned int i    = wls->node[k];
    double             diag = 0., radius = 0.;
    for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
      {
        const unsigned int j = wls->col[e];
        if (j == i)
          diag += wls->weight[e];
        else if (disc.region[j] == Discretization<dim>::interior)
          radius += std::abs(wls->weight[e]);
      }
    return {std::abs(diag) + radius, diag <= 0. && radius <= std::abs(diag) * (1. + 1e-12)};
  }

  template <int dim>
  bool
  DiffusionOperator<dim>::gershgorin_proves_stability() const
  {
    bool ok = true;
    if (wls)
      for (unsigned int k = 0; k < wls->node.size(); ++k)
        ok = ok && wls_gershgorin(k).second;
    return !Utilities::MPI::logical_or(!ok, disc.get_mpi_communicator());
  }

  template <int dim>
  void
  DiffusionOperator<dim>::assemble_backward_euler(const double                   dt,
                                                  TrilinosWrappers::SparseMatrix &matrix,
                                                  const Vector                   *phase) const
  {
    AssertThrow(!corrosion || phase != nullptr,
                ExcMessage("The corrosion model needs the phase field."));
    const auto &nb   = disc.neighborhood;
    const auto &part = *disc.partitioner();
    const auto  comm = disc.get_mpi_communicator();

    auto global = [&](const unsigned int local) { return part.local_to_global(local); };
    auto solid  = [&](const unsigned int local) {
      return phase != nullptr && corrosion && phase->local_element(local) > 0.5;
    };

    // Only owned rows are written; columns of ghost nodes are off-processor.
    TrilinosWrappers::SparsityPattern sp(part.locally_owned_range(),
                                         part.locally_owned_range(),
                                         comm,
                                         disc.neighborhood.stencil_size + 1);
    std::vector<types::global_dof_index> cols;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        cols.clear();
        cols.push_back(global(i));
        if (disc.region[i] == Discretization<dim>::interior)
          for (std::uint64_t k = nb.row_start[i]; k < nb.row_start[i + 1]; ++k)
            if (disc.region[nb.col[k]] == Discretization<dim>::interior)
              cols.push_back(global(nb.col[k]));
        sp.add_entries(global(i), cols.begin(), cols.end());
      }
    sp.compress();
    matrix.reinit(sp);

    std::vector<double> values;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        cols.clear();
        values.clear();
        cols.push_back(global(i));
        values.push_back(0.);
        if (disc.region[i] != Discretization<dim>::interior)
          {
            values[0] = 1.;
          }
        else
          {
            const double *w   = geometric_weight.data() + nb.table_start[i];
            double        sum = 0.;
            for (std::uint64_t k = nb.row_start[i]; k < nb.row_start[i + 1]; ++k)
              {
                const unsigned int j = nb.col[k];
                const double a = bond_kappa(solid(i), solid(j)) * w[k - nb.row_start[i]];
                sum += a;
                if (disc.region[j] == Discretization<dim>::interior)
                  {
                    cols.push_back(global(j));
                    values.push_back(-a);
                  }
              }
            values[0] = 1. / dt + sum;
          }
        matrix.set(global(i), cols.size(), cols.data(), values.data());
      }
    matrix.compress(VectorOperation::insert);
  }

  template <int dim>
  void
  DiffusionOperator<dim>::add_constrained_coupling(const Vector &C,
                                                   Vector       &rhs,
                                                   const Vector *phase) const
  {
    const auto &nb    = disc.neighborhood;
    auto        solid = [&](const unsigned int local) {
      return phase != nullptr && corrosion && phase->local_element(local) > 0.5;
    };
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        if (disc.region[i] != Discretization<dim>::interior)
          continue;
        const double *w = geometric_weight.data() + nb.table_start[i];
        double        s = 0.;
        for (std::uint64_t k = nb.row_start[i]; k < nb.row_start[i + 1]; ++k)
          {
            const unsigned int j = nb.col[k];
            if (disc.region[j] != Discretization<dim>::interior)
              s += bond_kappa(solid(i), solid(j)) * w[k - nb.row_start[i]] *
                   C.local_element(j);
          }
        rhs.local_element(i) += s;
      }
  }

  template class DiffusionOperator<1>;
  template class DiffusionOperator<2>;
  template class DiffusionOperator<3>;
} // namespace PeriDEAL
