#include <deal.II/base/mpi.h>

#include <perideal/models/bond_damage.h>
#include <perideal/base/exceptions.h>
#include <perideal/models/bond_based.h>
#include <perideal/models/lps.h>

#include <cmath>
#include <limits>

namespace PeriDEAL
{
  void
  LPSModelParameters::declare_parameters(ParameterHandler &prm)
  {
    prm.declare_entry("Influence function", "constant", Patterns::Selection("constant|linear"),
                      "omega_0 = 1 (2.12) or omega_1 = 1 - r/delta (2.13).");
    prm.declare_entry("Bulk modulus", "1", Patterns::Double(), "K (> 0).");
    prm.declare_entry("Shear modulus", "1", Patterns::Double(), "G (> 0).");
    prm.declare_entry("Critical stretch", "0", Patterns::Double(),
                      "s0 (>= 0) of the bond-breaking criterion on the linearized "
                      "stretch; 0: s0 from the fracture energy, or bonds never break.");
    prm.declare_entry("Fracture energy", "0", Patterns::Double(),
                      "G0 (>= 0): s0 = sqrt(5 G0 / (9 K delta)) (3D) or sqrt(pi G0 / (3 (K + "
                      "G/3) delta)) (2D plane strain) for omega_0 (see lps_critical_stretch); "
                      "used if Critical stretch = 0; 0: bonds never break.");
  }

  void
  LPSModelParameters::parse_parameters(ParameterHandler &prm)
  {
    omega         = parse_influence_function(prm.get("Influence function"), "Model/Influence function");
    bulk_modulus  = prm.get_double("Bulk modulus");
    shear_modulus = prm.get_double("Shear modulus");
    check_parameter(bulk_modulus > 0., "Model/Bulk modulus", bulk_modulus, "a positive number");
    check_parameter(shear_modulus > 0., "Model/Shear modulus", shear_modulus, "a positive number");
    critical_stretch = prm.get_double("Critical stretch");
    check_parameter(critical_stretch >= 0., "Model/Critical stretch", critical_stretch,
                    "a non-negative number (0: no bond breaking)");
    fracture_energy = prm.get_double("Fracture energy");
    check_parameter(fracture_energy >= 0., "Model/Fracture energy", fracture_energy,
                    "a non-negative number (0: no bond breaking)");
  }

  double
  lps_critical_stretch(const unsigned int      dim,
                       const InfluenceFunction omega,
                       const double            delta,
                       const double            K_d,
                       const double            G0)
  {
    check_parameter(dim == 2 || dim == 3, "Dimension", dim, "2 or 3 for LPS");
    // c_eq = 4 W / (|S| int omega r^d) with W = d^2 K_d / 2 per s^2: the
    // bond-based micromodulus for E = 1 (plane strain) rescaled from its
    // CCM expansion energy to the LPS one.
    const double W     = 0.5 * dim * dim * K_d;
    const double c_eq  = bond_based_micromodulus(dim, omega, delta, 1., false) * W /
                        isotropic_expansion_energy(dim, 1., false);
    return bond_based_critical_stretch(dim, omega, delta, c_eq, G0);
  }

  template <int dim>
  LinearizedLPSOperator<dim>::LinearizedLPSOperator(const Discretization<dim> &discretization,
                                                    const LPSModelParameters  &p)
    : disc(discretization)
    , K_d(dim == 3 ? p.bulk_modulus : p.bulk_modulus + p.shear_modulus / 3.)
    , G(p.shear_modulus)
    , omega_in_use(p.omega)
    , s0(p.critical_stretch > 0. ? p.critical_stretch :
         p.fracture_energy > 0.  ? lps_critical_stretch(dim, p.omega, discretization.parameters().delta,
                                                        dim == 3 ? p.bulk_modulus :
                                                                   p.bulk_modulus + p.shear_modulus / 3.,
                                                        p.fracture_energy) :
                                   std::numeric_limits<double>::infinity())
  {
    check_parameter(p.bulk_modulus > 0., "Model/Bulk modulus", p.bulk_modulus, "a positive number");
    check_parameter(p.shear_modulus > 0., "Model/Shear modulus", p.shear_modulus,
                    "a positive number");
    check_parameter(p.critical_stretch >= 0., "Model/Critical stretch", p.critical_stretch,
                    "a non-negative number (0: no bond breaking)");
    check_parameter(p.fracture_energy >= 0., "Model/Fracture energy", p.fracture_energy,
                    "a non-negative number (0: no bond breaking)");
    const auto  &nb    = disc.neighborhood;
    const double delta = disc.parameters().delta;
    // omega at min(r, delta): bonds of the partial-volume shell beyond delta
    // keep the horizon value, weighted by beta (as in the bond-based model).
    bond_coefficient.resize(nb.bond_length.size());
    for (std::size_t t = 0; t < bond_coefficient.size(); ++t)
      bond_coefficient[t] =
        influence(p.omega, std::min(nb.bond_length[t], delta), delta) * nb.bond_weight[t];

    disc.initialize_vector(m);
    disc.initialize_vector(theta);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const double *coef = bond_coefficient.data() + nb.table_start[i];
        const double *len  = nb.bond_length.data() + nb.table_start[i];
        double        s    = 0.;
        for (std::uint64_t k = 0; k < nb.row_start[i + 1] - nb.row_start[i]; ++k)
          s += coef[k] * len[k] * len[k];
        m.local_element(i) = s;
      }
    m.update_ghost_values();
    broken_flag.assign(nb.n_bonds(), 0);
  }

  template <int dim>
  void
  LinearizedLPSOperator<dim>::initialize(VectorField &field) const
  {
    for (auto &v : field)
      disc.initialize_vector(v);
  }

  template <int dim>
  void
  LinearizedLPSOperator<dim>::compute_dilatation(const VectorField &u, Vector &th) const
  {
    const auto                    &nb = disc.neighborhood;
    const std::vector<Point<dim>> &x  = disc.position;
    std::array<const double *, dim> ud;
    for (unsigned int d = 0; d < dim; ++d)
      ud[d] = u[d].begin();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        if (!wls_row.empty() && wls_row[i] >= 0)
          {
            // theta_i = L_theta Q-bar_i U-bar_i: dim weights per collocation node.
            const auto &w = wls->weights(0);
            double      s = 0.;
            for (auto e = wls->row_start[wls_row[i]]; e < wls->row_start[wls_row[i] + 1]; ++e)
              for (unsigned int d = 0; d < dim; ++d)
                s += w[e * dim + d] * ud[d][wls->col[e]];
            th.local_element(i) = s;
            continue;
          }
        const std::uint64_t begin = nb.row_start[i];
        const double       *coef  = bond_coefficient.data() + nb.table_start[i];
        double              s     = 0.;
        for (std::uint64_t b = begin; b < nb.row_start[i + 1]; ++b)
          {
            if (broken_flag[b])
              continue;
            const std::int32_t j  = nb.col[b];
            double             xe = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              xe += (x[j][d] - x[i][d]) * (ud[d][j] - ud[d][i]);
            s += coef[b - begin] * xe;
          }
        const double mi     = m.local_element(i);
        th.local_element(i) = mi > 0. ? dim * s / mi : 0.;
      }
  }

  template <int dim>
  void
  LinearizedLPSOperator<dim>::compute_forces(const VectorField &u, VectorField &force)
  {
    if (std::isfinite(s0))
      break_bonds(u);
    compute_dilatation(u, theta);
    theta.update_ghost_values();

    const auto                    &nb = disc.neighborhood;
    const std::vector<Point<dim>> &x  = disc.position;
    std::array<const double *, dim> ud;
    for (unsigned int d = 0; d < dim; ++d)
      ud[d] = u[d].begin();
    const double *md = m.begin();
    const double *td = theta.begin();
    // Volumetric factor d K_d - (d+2) G and deviatoric factor d (d+2) G.
    const double a_vol = dim * K_d - (dim + 2.) * G;
    const double a_dev = dim * (dim + 2.) * G;

    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        if (!wls_force.empty() && wls_force[i])
          {
            // (3.51): L_I Q_i Theta_i + L_J Q-bar_i U-bar_i.
            const auto  &wI = wls->weights(1);
            const auto  &wJ = wls->weights(2);
            const int    k  = wls_row[i];
            double       f[dim] = {};
            for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
              {
                const std::int32_t j = wls->col[e];
                for (unsigned int a = 0; a < dim; ++a)
                  {
                    f[a] += wI[e * dim + a] * td[j];
                    for (unsigned int b = 0; b < dim; ++b)
                      f[a] += wJ[(e * dim + a) * dim + b] * ud[b][j];
                  }
              }
            for (unsigned int d = 0; d < dim; ++d)
              force[d].local_element(i) = f[d];
            continue;
          }
        const std::uint64_t begin = nb.row_start[i];
        const double       *coef  = bond_coefficient.data() + nb.table_start[i];
        const double        inv_mi = md[i] > 0. ? 1. / md[i] : 0.;
        const double        q_i    = td[i] * inv_mi;
        double              f[dim] = {};
        for (std::uint64_t b = begin; b < nb.row_start[i + 1]; ++b)
          {
            if (broken_flag[b])
              continue;
            const std::int32_t j = nb.col[b];
            double             xi[dim], r2 = 0., xe = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              {
                xi[d] = x[j][d] - x[i][d];
                r2 += xi[d] * xi[d];
                xe += xi[d] * (ud[d][j] - ud[d][i]);
              }
            const double inv_mj = md[j] > 0. ? 1. / md[j] : 0.;
            const double scale =
              coef[b - begin] * (a_vol * (q_i + td[j] * inv_mj) + a_dev * (inv_mi + inv_mj) * xe / r2);
            for (unsigned int d = 0; d < dim; ++d)
              f[d] += scale * xi[d];
          }
        for (unsigned int d = 0; d < dim; ++d)
          force[d].local_element(i) = f[d];
      }
  }

  template <int dim>
  void
  LinearizedLPSOperator<dim>::strain_energy_density(const VectorField &u, Vector &W) const
  {
    Vector th;
    disc.initialize_vector(th);
    compute_dilatation(u, th);
    const auto &nb = disc.neighborhood;
    const auto &x  = disc.position;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        if (!wls_force.empty() && wls_force[i])
          {
            // (2.14) on the fitted polynomial: K_d theta^2/2 + alpha/2 c^T M c,
            // c_(a alpha) = sum_j N_alpha,j u_a,j the fit coefficients.
            const auto        &N  = wls->weights(3);
            const unsigned int np = wls->n_basis(), n = dim * np;
            const int          k  = wls_row[i];
            std::vector<double> c(n, 0.);
            for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
              for (unsigned int a = 0; a < dim; ++a)
                for (unsigned int al = 0; al < np; ++al)
                  c[a * np + al] += N[e * np + al] * u[a].local_element(wls->col[e]);
            double dev = 0.;
            for (unsigned int x = 0; x < n; ++x)
              for (unsigned int y = 0; y < n; ++y)
                dev += c[x] * wls_dev_moment[x * n + y] * c[y];
            const double ti    = th.local_element(i);
            W.local_element(i) = 0.5 * K_d * ti * ti + 0.5 * wls_alpha * dev;
            continue;
          }
        const std::uint64_t begin = nb.row_start[i];
        const double       *coef  = bond_coefficient.data() + nb.table_start[i];
        const double        ti    = th.local_element(i);
        const double        mi    = m.local_element(i);
        double              w     = 0.;
        for (std::uint64_t b = begin; b < nb.row_start[i + 1]; ++b)
          {
            if (broken_flag[b])
              continue;
            const std::int32_t j  = nb.col[b];
            double             r2 = 0., xe = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              {
                const double xi = x[j][d] - x[i][d];
                r2 += xi * xi;
                xe += xi * (u[d].local_element(j) - u[d].local_element(i));
              }
            const double r  = std::sqrt(r2);
            const double ed = xe / r - ti * r / dim;
            w += coef[b - begin] * ed * ed;
          }
        const double alpha = mi > 0. ? dim * (dim + 2.) * G / mi : 0.;
        W.local_element(i) = 0.5 * K_d * ti * ti + 0.5 * alpha * w;
      }
  }

  template <int dim>
  double
  LinearizedLPSOperator<dim>::total_strain_energy(const VectorField &u) const
  {
    Vector W;
    disc.initialize_vector(W);
    strain_energy_density(u, W);
    double e = 0.;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      e += W.local_element(i) * disc.volume[i];
    return Utilities::MPI::sum(e, disc.get_mpi_communicator());
  }

  template <int dim>
  void
  LinearizedLPSOperator<dim>::break_bonds(const VectorField &u)
  {
    const auto &nb = disc.neighborhood;
    const auto &x  = disc.position;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
        {
          if (broken_flag[b])
            continue;
          // xi and eta from positions so that row j's copy computes the
          // bitwise same stretch (both factors change sign).
          const std::int32_t j  = nb.col[b];
          double             r2 = 0., xe = 0.;
          for (unsigned int d = 0; d < dim; ++d)
            {
              const double xi = x[j][d] - x[i][d];
              r2 += xi * xi;
              xe += xi * (u[d].local_element(j) - u[d].local_element(i));
            }
          if (xe / r2 > s0)
            broken_flag[b] = 1;
        }
  }

  template <int dim>
  void
  LinearizedLPSOperator<dim>::set_broken_flags(const std::vector<std::uint8_t> &flags)
  {
    AssertThrow(flags.size() == broken_flag.size(),
                ExcMessage("One broken flag per bond of the owned rows is needed."));
    broken_flag = flags;
  }

  template <int dim>
  double
  LinearizedLPSOperator<dim>::critical_time_step(const double rho) const
  {
    const auto &nb = disc.neighborhood;
    const auto &x  = disc.position;
    // Q_k = d / m_k^2 sum_l w_kl 2 |xi_kl|_1, owned, then ghosts.
    Vector Q;
    disc.initialize_vector(Q);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const double *coef = bond_coefficient.data() + nb.table_start[i];
        double        s    = 0.;
        for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
          {
            double l1 = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              l1 += std::abs(x[nb.col[b]][d] - x[i][d]);
            s += coef[b - nb.row_start[i]] * 2. * l1;
          }
        const double mi    = m.local_element(i);
        Q.local_element(i) = mi > 0. ? dim * s / (mi * mi) : 0.;
      }
    Q.update_ghost_values();
    const double a_vol = std::abs(dim * K_d - (dim + 2.) * G);
    const double a_dev = dim * (dim + 2.) * G;
    double       bound = 0.;
    if (wls)
      {
        // WLS rows: |K_il| <= |W^J_il| + sum_j |W^I_ij| |d theta_j/d u_l|, so
        // the Gershgorin row sum is at most sum_e |W^J_e| + |W^I_e| S_col(e).
        Vector S;
        disc.initialize_vector(S);
        dilatation_sensitivity(S);
        S.update_ghost_values();
        const auto &wI = wls->weights(1);
        const auto &wJ = wls->weights(2);
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (wls_force[i])
            for (unsigned int a = 0; a < dim; ++a)
              {
                double s = 0.;
                for (auto e = wls->row_start[wls_row[i]]; e < wls->row_start[wls_row[i] + 1];
                     ++e)
                  {
                    s += std::abs(wI[e * dim + a]) * S.local_element(wls->col[e]);
                    for (unsigned int b = 0; b < dim; ++b)
                      s += std::abs(wJ[(e * dim + a) * dim + b]);
                  }
                bound = std::max(bound, s);
              }
      }
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        if (!wls_force.empty() && wls_force[i])
          continue;
        const double *coef   = bond_coefficient.data() + nb.table_start[i];
        const double  inv_mi = m.local_element(i) > 0. ? 1. / m.local_element(i) : 0.;
        for (unsigned int a = 0; a < dim; ++a)
          {
            double dev = 0., sum_xi = 0., vol_j = 0.;
            for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
              {
                const std::int32_t j = nb.col[b];
                const double       w = coef[b - nb.row_start[i]];
                double             xi[dim], r = 0., l1 = 0.;
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    xi[d] = x[j][d] - x[i][d];
                    r += xi[d] * xi[d];
                    l1 += std::abs(xi[d]);
                  }
                r                   = std::sqrt(r);
                const double inv_mj = m.local_element(j) > 0. ? 1. / m.local_element(j) : 0.;
                dev += 2. * w * a_dev * (inv_mi + inv_mj) * std::abs(xi[a]) / r * l1 / r;
                sum_xi += w * xi[a];
                vol_j += w * std::abs(xi[a]) * Q.local_element(j);
              }
            bound = std::max(bound, dev + a_vol * (std::abs(sum_xi) * Q.local_element(i) + vol_j));
          }
      }
    bound = Utilities::MPI::max(bound, disc.get_mpi_communicator());
    return bound > 0. ? 2. * std::sqrt(rho / bound) : std::numeric_limits<double>::infinity();
  }

  template <int dim>
  void
  LinearizedLPSOperator<dim>::dilatation_sensitivity(Vector &S) const
  {
    const auto &nb = disc.neighborhood;
    const auto &x  = disc.position;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        double s = 0.;
        if (!wls_row.empty() && wls_row[i] >= 0)
          {
            const auto &w = wls->weights(0);
            for (auto e = wls->row_start[wls_row[i]]; e < wls->row_start[wls_row[i] + 1]; ++e)
              for (unsigned int d = 0; d < dim; ++d)
                s += std::abs(w[e * dim + d]);
          }
        else
          {
            // d/m_i sum_j w_ij xi . (u_j - u_i): l1 norm 2 d/m_i sum_j w_ij |xi|_1.
            const double *coef = bond_coefficient.data() + nb.table_start[i];
            for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
              for (unsigned int d = 0; d < dim; ++d)
                s += 2. * coef[b - nb.row_start[i]] * std::abs(x[nb.col[b]][d] - x[i][d]);
            const double mi = m.local_element(i);
            s               = mi > 0. ? dim * s / mi : 0.;
          }
        S.local_element(i) = s;
      }
  }

  template <int dim>
  void
  LinearizedLPSOperator<dim>::set_wls_rows(const WlsParameters             &parameters,
                                           const std::vector<unsigned int> &rows)
  {
    check_parameter(!std::isfinite(s0), "Model/Critical stretch", s0,
                    "0 and Fracture energy 0 with the WLS quadrature (WLS rows have no bonds "
                    "to break)");
    const double delta = disc.parameters().delta;
    const auto   omega = omega_in_use;
    const double mbar  = lps_weighted_volume<dim>(omega, delta);
    const MonomialBasis<dim> basis(parameters.order);
    const unsigned int       np = basis.size();
    std::vector<WlsOperator> ops(4);
    ops[0] = {1, dim, vector_operator_rows<dim>(dim / mbar, omega, delta, basis)};
    ops[1] = {dim, 1, vector_operator_rows<dim>((dim * K_d - (dim + 2.) * G) / mbar, omega,
                                                delta, basis)};
    ops[2] = {dim, dim,
              pair_tensor_operator_rows<dim>(2. * dim * (dim + 2.) * G / mbar, omega, delta, 2.,
                                             basis)};
    ops[3] = {np, 1, std::vector<double>(np * np, 0.)};
    for (unsigned int a = 0; a < np; ++a)
      ops[3].rows[a * np + a] = 1.;
    wls = std::make_unique<WlsQuadrature<dim>>(parameters, delta, ops);
    wls_dev_moment = lps_deviatoric_moment_matrix<dim>(omega, delta, basis);
    wls_alpha      = dim * (dim + 2.) * G / mbar;

    // Force rows, and theta rows: the force rows and every owned node
    // with enough family nodes for a fit.
    const auto &nb = disc.neighborhood;
    wls_force.assign(disc.n_owned(), 0);
    for (const unsigned int i : rows)
      {
        AssertThrow(i < disc.n_owned() && disc.region[i] == Discretization<dim>::interior,
                    ExcMessage("WLS rows must be owned interior nodes."));
        wls_force[i] = 1;
      }
    std::vector<unsigned int> theta_rows;
    wls_row.assign(disc.n_owned(), -1);
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (wls_force[i] || nb.row_start[i + 1] - nb.row_start[i] + 1 >= wls->n_collocation())
        {
          wls_row[i] = theta_rows.size();
          theta_rows.push_back(i);
        }
    wls->build(disc.position, nb.row_start, nb.col, theta_rows);
  }

  template <int dim>
  std::uint64_t
  LinearizedLPSOperator<dim>::n_broken_bonds() const
  {
    return BondDamage::count_broken(broken_flag, disc.get_mpi_communicator());
  }

  template <int dim>
  void
  LinearizedLPSOperator<dim>::damage(Vector &phi) const
  {
    BondDamage::compute_damage(disc, broken_flag, phi);
  }

  template class LinearizedLPSOperator<2>;
  template class LinearizedLPSOperator<3>;
} // namespace PeriDEAL
