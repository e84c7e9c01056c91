#include <perideal/base/exceptions.h>
#include <perideal/models/hybrid_bond_based.h>

#include <chrono>
#include <complex>
#include <map>
#include <cmath>
#include <limits>
#include <sstream>

namespace PeriDEAL
{
  namespace
  {
    double
    seconds_since(const std::chrono::steady_clock::time_point &start)
    {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  } // namespace

  template <int dim>
  HybridBondBasedModel<dim>::HybridBondBasedModel(BondBasedOperator<dim>          &op,
                                                  const InfluenceFunction          omega,
                                                  const HybridMechanicsParameters &parameters,
                                                  const std::vector<bool>         &standard)
    : op(op)
    , disc(op.discretization())
    , prm(parameters)
    , s0(op.critical_stretch())
    , broken_flag(op.broken())
  {
    check_parameter(!op.is_linearized(), "Model/Bond-based/Linearized", "true",
                    "false for the adaptive hybrid configuration (its Omega_s rows are the "
                    "nonlinear PMB force with breaking)");
    check_parameter(prm.sigma > 0. && prm.sigma < 1., "Hybrid/Sigma", prm.sigma,
                    "a number in (0, 1)");
    AssertThrow(standard.size() == disc.n_owned(),
                ExcMessage("One Omega_s flag per owned node is needed."));

    disc.initialize_vector(wls_flag);
    disc.initialize_vector(critical);
    std::vector<unsigned int> rows;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      if (!standard[i] && disc.region[i] == Discretization<dim>::interior)
        {
          wls_flag.local_element(i) = 1.;
          rows.push_back(i);
        }
    wls_flag.update_ghost_values();
    wls = std::make_unique<WlsQuadrature<dim>>(prm.wls, op.micromodulus(),
                                               omega,
                                               disc.parameters().delta);
    wls->build(disc, rows);
    wls_row.assign(disc.n_owned(), -1);
    for (unsigned int k = 0; k < rows.size(); ++k)
      wls_row[rows[k]] = int(k);

    // Squared thresholds per bond table entry: (3.80) and breaking (2.34)
    // compare |y|^2 with them, without a square root.
    const auto &nb = disc.neighborhood;
    critical_length2.resize(nb.bond_length.size());
    breaking_length2.resize(nb.bond_length.size());
    const double s0_finite = std::isfinite(s0) ? s0 : std::numeric_limits<double>::max() / 4.;
    for (std::size_t t = 0; t < nb.bond_length.size(); ++t)
      {
        const double r = nb.bond_length[t];
        critical_length2[t] = std::isfinite(s0) ? std::pow(r * (1. + prm.sigma * s0), 2) :
                                                  std::numeric_limits<double>::infinity();
        breaking_length2[t] = std::isfinite(s0) ? std::pow(r * (1. + s0_finite), 2) :
                                                  std::numeric_limits<double>::infinity();
      }
    update_row_lists();
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::update_row_lists()
  {
    const auto &nb = disc.neighborhood;
    wls_mask.resize(disc.position.size());
    for (std::size_t k = 0; k < wls_mask.size(); ++k)
      wls_mask[k] = wls_flag.local_element(k) > 0.5;
    standard_rows.clear();
    active_wls_rows.clear();
    test_rows.clear();
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      {
        const bool w = wls_flag.local_element(i) > 0.5;
        (w ? active_wls_rows : standard_rows).push_back(i);
        bool touches = w;
        for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1] && !touches; ++b)
          touches = wls_flag.local_element(nb.col[b]) > 0.5;
        if (touches)
          test_rows.push_back(i);
      }
  }

  template <int dim>
  bool
  HybridBondBasedModel<dim>::switch_critical(const VectorField &u)
  {
    const auto        &nb      = disc.neighborhood;
    const unsigned int n_owned = disc.n_owned();
    const double      *w       = wls_flag.begin();
    const auto        &brk     = broken_flag;
    (void)w;
    double            *crit    = critical.begin();
    const double      *p       = deformed.data();
    (void)u;
    std::uint64_t n_critical = 0;
    const std::uint8_t *wf = wls_mask.data();
    for (const unsigned int i : test_rows)
      {
        const double       *pi    = p + std::size_t(dim) * i;
        const double       *L2    = critical_length2.data() + nb.table_start[i];
        const auto          begin = nb.row_start[i];
        const unsigned int  n     = nb.row_start[i + 1] - begin;
        const std::int32_t *col   = nb.col.data() + begin;
        const std::uint8_t *br    = brk.data() + begin;
        const std::int32_t  lower = std::int32_t(i), owned = std::int32_t(n_owned);
        const std::uint8_t  wi    = wf[i];
        // First a branch-free (vectorizable) count of the critical bonds: a
        // bond between owned nodes once (from its lower end), a bond to a
        // ghost from both ranks (bitwise the same |y|^2), unbroken, with an
        // end in Omega_w.
        unsigned int count = 0;
#pragma omp simd reduction(+ : count)
        for (unsigned int b = 0; b < n; ++b)
          {
            const std::int32_t j  = col[b];
            const double      *pj = p + std::size_t(dim) * j;
            double             l2 = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              l2 += (pj[d] - pi[d]) * (pj[d] - pi[d]);
            const bool tested = (j > lower || j >= owned) && br[b] == 0 && (wi | wf[j]) != 0;
            count += (tested && l2 >= L2[b]) ? 1u : 0u;
          }
        if (count == 0)
          continue;
        n_critical += count;
        const double *B2 = breaking_length2.data() + nb.table_start[i];
        for (unsigned int b = 0; b < n; ++b)
          {
            const std::int32_t j = col[b];
            if ((j < owned && j < lower) || br[b] || (wi | wf[j]) == 0)
              continue;
            const double *pj = p + std::size_t(dim) * j;
            double        l2 = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              l2 += (pj[d] - pi[d]) * (pj[d] - pi[d]);
            if (l2 >= L2[b])
              {
                crit[i] = 1.;
                if (j < owned)
                  crit[j] = 1.;
                // Counted once per bond (a ghost bond by the end with the lower id).
                if (l2 > B2[b] && (j < owned || disc.id[i] < disc.id[j]))
                  ++overstretched;
              }
          }
      }
    // One global sum per step; the ghost exchanges only when needed.
    if (Utilities::MPI::sum(n_critical, disc.get_mpi_communicator()) == 0)
      return false;
    critical.update_ghost_values();
    bool changed = false;
    for (unsigned int i = 0; i < n_owned; ++i)
      {
        if (w[i] == 0.)
          continue;
        bool hit = crit[i] > 0.;
        for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1] && !hit; ++b)
          hit = crit[nb.col[b]] > 0.;
        if (hit)
          {
            wls_flag.local_element(i) = 0.;
            changed                   = true;
          }
      }
    critical = 0.;
    critical.zero_out_ghost_values();
    wls_flag.update_ghost_values();
    update_row_lists();
    ++switch_events;
    return changed;
  }

  template <int dim>
  void
  HybridBondBasedModel<dim>::compute_forces(const VectorField &u, VectorField &force)
  {
    auto start = std::chrono::steady_clock::now();
    // Deformed positions x - x_c + u (x_c the lattice centre, the same on
    // every rank) of all local nodes, interleaved.
    const std::vector<Point<dim>> &x       = disc.position;
    const std::size_t              n_local = x.size();
    deformed.resize(n_local * dim);
    std::array<int, dim> mid;
    for (unsigned int d = 0; d < dim; ++d)
      mid[d] = int(disc.lattice_size()[d] / 2);
    const Point<dim> xc = disc.lattice_point(mid);
    for (unsigned int d = 0; d < dim; ++d)
      {
        const double *ud = u[d].begin();
        for (std::size_t i = 0; i < n_local; ++i)
          deformed[dim * i + d] = (x[i][d] - xc[d]) + ud[i];
      }
    if (!test_rows.empty() || Utilities::MPI::n_mpi_processes(disc.get_mpi_communicator()) > 1)
      switch_critical(u);
    seconds[0] += seconds_since(start);

    // Omega_s: the nonlinear PMB force (3.1) with breaking (2.34), as in
    // BondBasedOperator: force k (l - r) y / l, break when l - r > s0 r.
    start               = std::chrono::steady_clock::now();
    const auto   &nb    = disc.neighborhood;
    auto         &flags = broken_flag;
    bool          broke = false;
    const double *p     = deformed.data();
    const double *coef  = op.bond_coefficients().data();
    for (const unsigned int i : standard_rows)
      {
        const double       *pi = p + std::size_t(dim) * i;
        const double       *k  = coef + nb.table_start[i];
        const double       *r  = nb.bond_length.data() + nb.table_start[i];
        const auto          begin = nb.row_start[i];
        const unsigned int  n     = nb.row_start[i + 1] - begin;
        const std::int32_t *col   = nb.col.data() + begin;
        std::uint8_t       *br    = flags.data() + begin;
        // Branch-free so that it vectorizes: a broken bond (or one that
        // breaks now) contributes zero.
        double        f0 = 0., f1 = 0., f2 = 0.;
        unsigned int  n_break = 0;
#pragma omp simd reduction(+ : f0, f1, f2, n_break)
        for (unsigned int b = 0; b < n; ++b)
          {
            const double *pj = p + std::size_t(dim) * col[b];
            double        y[3] = {0., 0., 0.};
            for (unsigned int d = 0; d < dim; ++d)
              y[d] = pj[d] - pi[d];
            double l2 = y[0] * y[0];
            for (unsigned int d = 1; d < dim; ++d)
              l2 = std::fma(y[d], y[d], l2);
            const double l      = std::sqrt(l2);
            const double dl     = l - r[b];
            const bool   alive  = br[b] == 0;
            const bool   breaks = alive && dl > s0 * r[b];
            n_break += breaks ? 1u : 0u;
            const double scale = (alive && !breaks) ? k[b] * dl / l : 0.;
            f0 += scale * y[0];
            f1 += scale * y[1];
            f2 += scale * y[2];
          }
        if (n_break > 0)
          {
            broke = true;
            for (unsigned int b = 0; b < n; ++b)
              if (br[b] == 0)
                {
                  const double *pj = p + std::size_t(dim) * col[b];
                  double        l2 = 0.;
                  double        y[dim];
                  for (unsigned int d = 0; d < dim; ++d)
                    y[d] = pj[d] - pi[d];
                  l2 = y[0] * y[0];
                  for (unsigned int d = 1; d < dim; ++d)
                    l2 = std::fma(y[d], y[d], l2);
                  if (std::sqrt(l2) - r[b] > s0 * r[b])
                    br[b] = 1;
                }
          }
        const double f[3] = {f0, f1, f2};
        for (unsigned int d = 0; d < dim; ++d)
          force[d].local_element(i) = f[d];
      }
    op_stale = op_stale || broke;
    seconds[1] += seconds_since(start);

    // Omega_w: F_i = sum_c W_ic u_c, dim x dim blocks (row-major).
    start = std::chrono::steady_clock::now();
    std::array<const double *, dim> ud;
    for (unsigned int d = 0; d < dim; ++d)
      ud[d] = u[d].begin();
    constexpr unsigned int c2 = dim * dim;
    for (const unsigned int i : active_wls_rows)
      {
        const unsigned int k = wls_row[i];
        double             f[dim] = {};
        for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
          {
            const double *W = wls->weight.data() + c2 * e;
            const auto    j = wls->col[e];
            for (unsigned int a = 0; a < dim; ++a)
              for (unsigned int b = 0; b < dim; ++b)
                f[a] += W[a * dim + b] * ud[b][j];
          }
        for (unsigned int d = 0; d < dim; ++d)
          force[d].local_element(i) = f[d];
      }
    seconds[2] += seconds_since(start);
  }

  template <int dim>
  double
  HybridBondBasedModel<dim>::critical_time_step(const double rho) const
  {
    // Bound of lambda_max(-M) for the WLS rows: on a lattice the rows of
    // Omega_w are translates of a few collocation patterns, and on plane
    // waves u = a exp(i k.x) a pattern acts as the dim x dim symbol
    // M(k) = sum_c W_c exp(i k.(x_c - x_i)); rho(M(k)) <= ||M(k)||_inf is
    // maximized over a grid of k in the Brillouin zone [-pi/dx, pi/dx]^dim.
    // (A Gershgorin bound over the collocation nodes, sum_c ||W_c||, is
    // 2.5x too pessimistic for WLS-2 because of its negative weights.)
    // Verlet is stable for dt <= 2 / sqrt(lambda_max / rho).
    constexpr unsigned int   c2 = dim * dim;
    const double             dx = disc.parameters().dx;
    std::map<std::vector<long>, unsigned int> patterns; // offsets / (dx/8) -> first row
    for (unsigned int k = 0; k < wls->node.size(); ++k)
      {
        std::vector<long> key;
        for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
          for (unsigned int d = 0; d < dim; ++d)
            key.push_back(std::lround(8. * (disc.position[wls->col[e]][d] -
                                            disc.position[wls->node[k]][d]) / dx));
        patterns.emplace(key, k);
      }
    const unsigned int n_k = dim == 3 ? 17 : 41;
    double             lambda = 0.;
    for (const auto &[key, k] : patterns)
      {
        const unsigned int i = wls->node[k];
        unsigned int       n_total = 1;
        for (unsigned int d = 0; d < dim; ++d)
          n_total *= n_k;
        for (unsigned int q = 0; q < n_total; ++q)
          {
            Tensor<1, dim> wave;
            for (unsigned int d = 0, r = q; d < dim; ++d, r /= n_k)
              wave[d] = M_PI / dx * (-1. + 2. * double(r % n_k) / double(n_k - 1));
            std::complex<double> M[c2] = {};
            for (auto e = wls->row_start[k]; e < wls->row_start[k + 1]; ++e)
              {
                const std::complex<double> phase =
                  std::exp(std::complex<double>(0., wave * (disc.position[wls->col[e]] -
                                                            disc.position[i])));
                for (unsigned int ab = 0; ab < c2; ++ab)
                  M[ab] += wls->weight[c2 * e + ab] * phase;
              }
            for (unsigned int a = 0; a < dim; ++a)
              {
                double row = 0.;
                for (unsigned int b = 0; b < dim; ++b)
                  row += std::abs(M[a * dim + b]);
                lambda = std::max(lambda, row);
              }
          }
      }
    lambda = Utilities::MPI::max(lambda, disc.get_mpi_communicator());
    const double dt_wls =
      lambda > 0. ? 2. * std::sqrt(rho / lambda) : std::numeric_limits<double>::max();
    return std::min(dt_wls, op.critical_time_step(rho));
  }

  template <int dim>
  std::string
  HybridBondBasedModel<dim>::description() const
  {
    std::ostringstream s;
    s << "adaptive hybrid (standard PMB on Omega_s, WLS-" << prm.wls.order << " with "
      << wls->n_collocation() << " collocation nodes on Omega_w, sigma = " << prm.sigma
      << ", c = " << op.micromodulus() << ", s0 = " << s0 << ")";
    return s.str();
  }

  template <int dim>
  types::global_dof_index
  HybridBondBasedModel<dim>::n_standard_nodes() const
  {
    types::global_dof_index n = 0;
    for (unsigned int i = 0; i < disc.n_owned(); ++i)
      n += wls_flag.local_element(i) < 0.5 ? 1 : 0;
    return Utilities::MPI::sum(n, disc.get_mpi_communicator());
  }

  template <int dim>
  std::uint64_t
  HybridBondBasedModel<dim>::n_overstretched_bonds() const
  {
    return Utilities::MPI::sum(overstretched, disc.get_mpi_communicator());
  }

  template class HybridBondBasedModel<1>;
  template class HybridBondBasedModel<2>;
  template class HybridBondBasedModel<3>;
} // namespace PeriDEAL
