#include <perideal/abc/absorbing_layer.h>
#include <perideal/abc/ebf_cloud.h>
#include <perideal/abc/ebf_elastic_abc.h>
#include <perideal/base/exceptions.h>

#include <deal.II/lac/lapack_full_matrix.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace PeriDEAL
{
  namespace Abc
  {
    ElasticDispersion
    ElasticDispersion::local(const double E, const bool plane_stress, const double rho,
                             const double damping)
    {
      const double nu  = plane_stress ? 1. / 3. : 0.25;
      const double cp2 = plane_stress ? E / (rho * (1. - nu * nu)) :
                                        E * (1. - nu) / (rho * (1. + nu) * (1. - 2. * nu));
      const double cs2 = E / (2. * rho * (1. + nu));
      ElasticDispersion w;
      w.name     = "local";
      w.damping  = damping;
      w.acoustic = [cp2, cs2](const Tensor<1, 2> &k) {
        // c_S^2 |k|^2 I + (c_P^2 - c_S^2) k k^T.
        Tensor<2, 2> A = outer_product(k, k) * (cp2 - cs2);
        for (unsigned int d = 0; d < 2; ++d)
          A[d][d] += cs2 * (k * k);
        return A;
      };
      return w;
    }

    ElasticDispersion
    ElasticDispersion::stencil(const std::vector<Tensor<1, 2>> &offsets,
                               const std::vector<double>       &weights,
                               const double                     rho,
                               const double                     damping,
                               const std::string               &name)
    {
      AssertDimension(offsets.size(), weights.size());
      ElasticDispersion w;
      w.name     = name;
      w.damping  = damping;
      w.acoustic = [offsets, weights, rho](const Tensor<1, 2> &k) {
        Tensor<2, 2> A;
        for (unsigned int j = 0; j < offsets.size(); ++j)
          A += (weights[j] * (1. - std::cos(k * offsets[j])) / rho) *
               outer_product(offsets[j], offsets[j]);
        return A;
      };
      return w;
    }

    ElasticDispersion
    ElasticDispersion::discrete(const BondBasedModelParameters &model,
                                const LatticeParameters        &lattice,
                                const double                    rho,
                                const double                    damping)
    {
      const double delta = lattice.delta, dx = lattice.dx;
      const double c     = model.micromodulus > 0. ?
                             model.micromodulus :
                             bond_based_micromodulus(2, model.omega, delta, model.youngs_modulus,
                                                     model.plane_stress);
      // The lattice family of the origin as Discretization builds it.
      const int                 m = static_cast<int>(std::ceil(delta / dx + 0.5)) + 1;
      std::vector<Tensor<1, 2>> offsets;
      std::vector<double>       weights;
      for (int lx = -m; lx <= m; ++lx)
        for (int ly = -m; ly <= m; ++ly)
          {
            Tensor<1, 2> xi;
            xi[0]          = lx * dx;
            xi[1]          = ly * dx;
            const double r = xi.norm();
            if (r == 0.)
              continue;
            const double beta = Discretization<2>::volume_factor(r, delta, dx, lattice.partial_volume);
            if (beta <= 0.)
              continue;
            offsets.push_back(xi);
            // Linearized bond force (2.32): c omega beta V xi xi^T eta / |xi|^3.
            weights.push_back(c * influence(model.omega, std::min(r, delta), delta) * beta * dx * dx /
                              (r * r * r));
          }
      return stencil(offsets, weights, rho, damping, "discrete");
    }

    std::array<ElasticDispersion::Mode, 2>
    ElasticDispersion::modes(const double k, const Tensor<1, 2> &n_in) const
    {
      const Tensor<1, 2> n = n_in / n_in.norm();
      Tensor<1, 2>       np;
      np[0] = -n[1];
      np[1] = n[0];
      const Tensor<2, 2> A    = acoustic(std::abs(k) * n);
      const double       mean = 0.5 * (A[0][0] + A[1][1]);
      const double       half = 0.5 * (A[0][0] - A[1][1]);
      const double       rad  = std::sqrt(half * half + A[0][1] * A[0][1]);
      std::array<Mode, 2> out;
      std::array<double, 2> lambda;
      if (rad <= 1e-12 * std::abs(mean) || rad == 0.)
        {
          // Degenerate (k = 0): any basis; the one of the direction.
          lambda = {{mean, mean}};
          out[0].polarization = n;
          out[1].polarization = np;
        }
      else
        {
          std::array<Tensor<1, 2>, 2> e;
          std::array<double, 2>       l;
          for (unsigned int b = 0; b < 2; ++b)
            {
              l[b] = mean + (b == 0 ? rad : -rad);
              // (A - l I) e = 0: the better conditioned of the two rows.
              Tensor<1, 2> v1, v2;
              v1[0] = A[0][1];
              v1[1] = l[b] - A[0][0];
              v2[0] = l[b] - A[1][1];
              v2[1] = A[0][1];
              e[b]  = v1.norm() > v2.norm() ? v1 / v1.norm() : v2 / v2.norm();
            }
          // P: the polarization nearer to the direction.
          const unsigned int p = std::abs(e[0] * n) >= std::abs(e[1] * n) ? 0 : 1;
          out[0].polarization  = e[p] * (e[p] * n < 0. ? -1. : 1.);
          out[1].polarization  = e[1 - p] * (e[1 - p] * np < 0. ? -1. : 1.);
          lambda               = {{l[p], l[1 - p]}};
        }
      for (unsigned int b = 0; b < 2; ++b)
        {
          const std::complex<double> root =
            std::sqrt(std::complex<double>(lambda[b] - damping * damping, 0.));
          out[b].frequency = k < 0 ? -root : root;
        }
      return out;
    }

    void
    EbfElasticAbc::reinit(const std::vector<Point<2>>                &points,
                          const std::vector<types::global_dof_index> &ids,
                          const std::vector<unsigned int>            &absorbing_in,
                          const std::vector<Tensor<1, 2>>            &normals,
                          const ElasticDispersion                    &dispersion,
                          const double                                dt,
                          const double                                dx,
                          const WaveAbcParameters                    &prm,
                          const MPI_Comm                              comm)
    {
      AssertDimension(points.size(), ids.size());
      AssertDimension(absorbing_in.size(), normals.size());
      check_parameter(prm.n_time_levels == 1 || prm.n_time_levels == 2,
                      "Absorbing boundary/Time levels", prm.n_time_levels, "1 or 2");
      check_parameter(prm.wave_number_range > 0. && prm.wave_number_range <= M_PI / dx * (1. + 1e-12),
                      "Absorbing boundary/Wave number range", prm.wave_number_range,
                      "0 < Delta k <= pi/dx = " + std::to_string(M_PI / dx) + " (4.167)");
      check_parameter(prm.cloud_radius > 0., "Absorbing boundary/Cloud radius", prm.cloud_radius, "> 0");
      check_parameter(prm.fit_form == "value" || prm.fit_form == "increment", "Absorbing boundary/Fit form",
                      prm.fit_form, "value or increment");
      check_parameter(prm.pseudo_inverse_regularization == "truncate" ||
                        (prm.pseudo_inverse_regularization == "tikhonov" && prm.pseudo_inverse_tolerance > 0.),
                      "Absorbing boundary/Pseudo-inverse regularization", prm.pseudo_inverse_regularization,
                      "truncate, or tikhonov with a Pseudo-inverse tolerance > 0");
      check_parameter(prm.curvature_radius == 0. || prm.curvature_radius > prm.cloud_radius,
                      "Absorbing boundary/Curvature radius", prm.curvature_radius,
                      "0 (plane modes) or > the cloud radius " + std::to_string(prm.cloud_radius));
      const bool increment = prm.fit_form == "increment";
      const bool tikhonov  = prm.pseudo_inverse_regularization == "tikhonov";
      absorbing = absorbing_in;
      cloud_start.assign(1, 0);
      cloud_index.clear();
      vg.clear();
      vh.clear();
      stats = WaveCloudStatistics();

      // Mode parameters (4.154), conjugate-closed: k in [-Delta k, Delta k].
      std::vector<double> k, phi;
      for (unsigned int m = 0; m <= prm.n_wave_numbers; ++m)
        k.push_back(prm.wave_number_range * (-1. + 2. * m / prm.n_wave_numbers));
      if (prm.n_directions == 0)
        phi.push_back(0.);
      else
        for (unsigned int l = 0; l <= prm.n_directions; ++l)
          phi.push_back(prm.direction_range * (-1. + 2. * l / prm.n_directions));
      const unsigned int n_cols = 2 * k.size() * phi.size();
      stats.n_modes             = n_cols;

      const EbfCloudBuilder<2> builder(points, ids, prm.cloud_radius, prm.cone_angle, dx);
      const std::complex<double> I(0., 1.);
      double       max_cond = 0., max_norm = 0.;
      unsigned int min_size = std::numeric_limits<unsigned int>::max(), max_size = 0;
      unsigned int n_thinned = 0, max_stride = 1;
      const bool   first_order = prm.method == "first order";
      if (first_order)
        stats.n_modes = 0;
      // The undamped relation for the long-wave speeds of the first-order ABC.
      ElasticDispersion undamped = dispersion;
      undamped.damping           = 0.;
      for (unsigned int a = 0; a < absorbing.size(); ++a)
        {
          const unsigned int  i = absorbing[a];
          const Tensor<2, 2>  R = EbfWaveAbc<2>::local_frame(normals[a]);
          if (first_order)
            {
              // Lysmer-type one-way condition by forward Euler (the vector
              // analogue of the scalar first-order ABC of EbfWaveAbc):
              // u^{n+1} = (1 - d dt) u^n - dt C du/dn, C = c_P n n^T + c_S
              // (I - n n^T) with the long-wave (k -> 0) P and S speeds of
              // the relation along n (the local Navier limit for "local"),
              // du/dn from a linear least-squares fit over x_i and the cone
              // points within min(d_inf, 2 dx) (upwind); v alike.
              const Tensor<1, 2> n = normals[a] / normals[a].norm();
              const double       eps = 1e-4;
              const auto         md  = undamped.modes(eps, n);
              // C from the two modes (their polarizations are orthonormal):
              // for the discrete relation they deviate from n, n_perp by
              // the lattice anisotropy only.
              Tensor<2, 2> C;
              for (unsigned int b = 0; b < 2; ++b)
                C += (std::abs(md[b].frequency) / eps) * outer_product(md[b].polarization, md[b].polarization);
              const auto                             cone = builder.cone(i, R);
              std::vector<EbfCloudBuilder<2>::Entry> sel;
              Eigen::MatrixXd                        A;
              Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
              // Within min(d_inf, 2 dx) first; when these are collinear (a
              // lattice-aligned normal with a cone of half-angle >= pi/4 holds
              // only (-dx, 0), (-2 dx, 0) there) the whole cone (d_inf).
              for (const double radius : {std::min(prm.cloud_radius, 2. * dx), prm.cloud_radius})
                {
                  sel.assign(1, cone[0]);
                  for (unsigned int c = 1; c < cone.size(); ++c)
                    if (cone[c].second.norm() <= radius * (1. + 1e-10))
                      sel.push_back(cone[c]);
                  A.resize(sel.size(), 3);
                  for (unsigned int q = 0; q < sel.size(); ++q)
                    {
                      A(q, 0) = 1.;
                      A(q, 1) = sel[q].second[0];
                      A(q, 2) = sel[q].second[1];
                    }
                  cod.compute(A);
                  if (cod.rank() == 3)
                    break;
                }
              check_parameter(cod.rank() == 3, "Absorbing boundary/Cloud radius", prm.cloud_radius,
                              "a radius whose cone behind absorbing node " + std::to_string(ids[i]) +
                                " holds enough points for a linear fit (first-order ABC)");
              const Eigen::MatrixXd P = cod.pseudoInverse();
              for (unsigned int q = 0; q < sel.size(); ++q)
                {
                  // Row 1 of P: d/dx bar = d/dn (x bar along the outward normal).
                  cloud_index.push_back(sel[q].first);
                  for (unsigned int p = 0; p < 2; ++p)
                    for (unsigned int r = 0; r < 2; ++r)
                      {
                        const double c = -dt * C[p][r] * P(1, q) +
                                         (q == 0 && p == r ? 1. - dt * dispersion.damping : 0.);
                        // Entry layout [p][q][level] (q = r): level n only;
                        // the same coefficients for u and v.
                        for (auto *w : {&vg, &vh})
                          {
                            w->push_back(c);
                            w->push_back(0.);
                          }
                        max_norm = std::max(max_norm, std::abs(c));
                      }
                }
              cloud_start.push_back(cloud_index.size());
              min_size = std::min<unsigned int>(min_size, sel.size());
              max_size = std::max<unsigned int>(max_size, sel.size());
              continue;
            }
          // Per column: local wave vector, rate -d - i omega~, polarization (global).
          std::vector<Tensor<1, 2>>         kv(n_cols), gamma(n_cols);
          std::vector<std::complex<double>> rate(n_cols);
          for (unsigned int l = 0; l < phi.size(); ++l)
            {
              Tensor<1, 2> dir;
              dir[0]                   = std::cos(phi[l]);
              dir[1]                   = std::sin(phi[l]);
              const Tensor<1, 2> dir_g = transpose(R) * dir;
              for (unsigned int m = 0; m < k.size(); ++m)
                {
                  const auto modes = dispersion.modes(k[m], dir_g);
                  for (unsigned int b = 0; b < 2; ++b)
                    {
                      const unsigned int c = 2 * (l * k.size() + m) + b;
                      kv[c]                = k[m] * dir;
                      gamma[c]             = modes[b].polarization;
                      rate[c]              = -dispersion.damping - I * modes[b].frequency;
                    }
                }
            }
          const auto cone = builder.cone(i, R);
          // Curved wave fronts (curvature_radius rho > 0, as the scalar
          // EbfWaveAbc): every mode is evaluated in the polar coordinates
          // about x_i - rho n, s = (r - rho, rho theta), with the
          // cylindrical amplitude sqrt(rho / r), and its polarization turns
          // with the local radial direction (a P mode along the normal stays
          // radial, an S mode tangential): outgoing cylindrical P and S waves.
          const double rho_c = prm.curvature_radius;
          const auto   mode  = [&](const Tensor<1, 2> &xbar, const double time, const unsigned int c,
                                  const unsigned int q) {
            Tensor<1, 2> s = xbar, g = gamma[c];
            double       amplitude = 1.;
            if (rho_c > 0.)
              {
                Tensor<1, 2> from_centre = xbar;
                from_centre[0] += rho_c;
                const double radius = from_centre.norm();
                const double theta  = std::atan2(from_centre[1], from_centre[0]);
                s[0]                = radius - rho_c;
                s[1]                = rho_c * theta;
                amplitude           = std::sqrt(rho_c / radius);
                // gamma in the local frame, turned by theta, back to global.
                const Tensor<1, 2> gl = R * g;
                Tensor<1, 2>       gr;
                gr[0] = std::cos(theta) * gl[0] - std::sin(theta) * gl[1];
                gr[1] = std::sin(theta) * gl[0] + std::cos(theta) * gl[1];
                g     = transpose(R) * gr;
              }
            return amplitude * g[q] * std::exp(I * (kv[c] * s) + rate[c] * time);
          };

          PseudoInverseFit fg, fh;
          bool             ok     = false;
          unsigned int     stride = 1;
          std::vector<EbfCloudBuilder<2>::Entry> cloud;
          for (; stride <= 8 && !ok; ++stride)
            {
              cloud = builder.thin(cone, stride);
              if (cloud.size() < 2)
                break;
              // Rows 4 j + 2 q + s: component q of cloud point j at t = -s dt (4.159)-(4.165).
              Eigen::MatrixXcd MG(4 * cloud.size(), n_cols), MH(4 * cloud.size(), n_cols);
              Eigen::MatrixXcd psi_g(2, n_cols), psi_h(2, n_cols);
              for (unsigned int c = 0; c < n_cols; ++c)
                {
                  for (unsigned int p = 0; p < 2; ++p)
                    {
                      psi_g(p, c) = mode(Tensor<1, 2>(), dt, c, p);
                      // Increment form: the fit extrapolates the change over
                      // one step (x_i's level-n value is added back below).
                      if (increment)
                        psi_g(p, c) -= mode(Tensor<1, 2>(), 0., c, p);
                      psi_h(p, c) = rate[c] * psi_g(p, c);
                    }
                  for (unsigned int j = 0; j < cloud.size(); ++j)
                    for (unsigned int s = 0; s < 2; ++s)
                      for (unsigned int q = 0; q < 2; ++q)
                        {
                          MG(4 * j + 2 * q + s, c) =
                            s < prm.n_time_levels ? mode(cloud[j].second, -double(s) * dt, c, q) : 0.;
                          MH(4 * j + 2 * q + s, c) = rate[c] * MG(4 * j + 2 * q + s, c);
                        }
                }
              fg = pseudo_inverse_fit(MG, psi_g, prm.pseudo_inverse_tolerance, tikhonov);
              fh = pseudo_inverse_fit(MH, psi_h, prm.pseudo_inverse_tolerance, tikhonov);
              if (increment)
                {
                  // + e_i: cloud[0] = x_i, column 2 p = component p at level n.
                  for (unsigned int p = 0; p < 2; ++p)
                    {
                      fg.V(p, 2 * p) += 1.;
                      fh.V(p, 2 * p) += 1.;
                    }
                  fg.max_norm = fg.V.cwiseAbs().maxCoeff();
                  fh.max_norm = fh.V.cwiseAbs().maxCoeff();
                }
              ok = fg.condition_number <= prm.max_condition_number &&
                   fh.condition_number <= prm.max_condition_number &&
                   fg.max_norm <= prm.max_update_norm && fh.max_norm <= prm.max_update_norm;
            }
          --stride;
          if (!ok)
            {
              std::ostringstream v;
              v << "condition numbers " << fg.condition_number << " (M_G), " << fh.condition_number
                << " (M_H), max |V_G| " << fg.max_norm << ", max |V_H| " << fh.max_norm
                << " for the absorbing node " << ids[i] << " at (" << points[i] << ") ("
                << cloud.size() << " cloud points at the last thinning stride " << stride << ", "
                << n_cols << " P and S modes)";
              throw ParameterError("Absorbing boundary/Wave number range, Number of wave numbers",
                                   v.str(),
                                   "a mode set with condition number <= " +
                                     std::to_string(prm.max_condition_number) + " and max |V| <= " +
                                     std::to_string(prm.max_update_norm) +
                                     " after thinning (reduce Delta k or the number of modes)");
            }
          if (stride > 1)
            ++n_thinned;
          max_stride = std::max(max_stride, stride);
          max_cond   = std::max({max_cond, fg.condition_number, fh.condition_number});
          max_norm   = std::max({max_norm, fg.max_norm, fh.max_norm});
          min_size   = std::min<unsigned int>(min_size, cloud.size());
          max_size   = std::max<unsigned int>(max_size, cloud.size());
          for (unsigned int j = 0; j < cloud.size(); ++j)
            {
              cloud_index.push_back(cloud[j].first);
              for (unsigned int p = 0; p < 2; ++p)
                for (unsigned int r = 0; r < 4; ++r)
                  {
                    vg.push_back(fg.V(p, 4 * j + r));
                    vh.push_back(fh.V(p, 4 * j + r));
                  }
            }
          cloud_start.push_back(cloud_index.size());
        }
      all_cloud_points = cloud_index;
      std::sort(all_cloud_points.begin(), all_cloud_points.end());
      all_cloud_points.erase(std::unique(all_cloud_points.begin(), all_cloud_points.end()),
                             all_cloud_points.end());
      stats.n_absorbing = Utilities::MPI::sum<types::global_dof_index>(absorbing.size(), comm);
      stats.max_condition_number = Utilities::MPI::max(max_cond, comm);
      stats.max_update_norm      = Utilities::MPI::max(max_norm, comm);
      stats.min_cloud_size       = Utilities::MPI::min(min_size, comm);
      stats.max_cloud_size       = Utilities::MPI::max(max_size, comm);
      stats.n_thinned            = Utilities::MPI::sum(n_thinned, comm);
      stats.max_stride           = Utilities::MPI::max(max_stride, comm);
    }

    void
    EbfElasticAbc::compute(const std::array<const double *, 2> &u,
                           const std::array<const double *, 2> &u_old,
                           const std::array<const double *, 2> &v,
                           const std::array<const double *, 2> &v_old,
                           std::vector<double>                 &u_new,
                           std::vector<double>                 &v_new) const
    {
      u_new.assign(2 * absorbing.size(), 0.);
      v_new.assign(2 * absorbing.size(), 0.);
      for (unsigned int a = 0; a < absorbing.size(); ++a)
        for (unsigned int c = cloud_start[a]; c < cloud_start[a + 1]; ++c)
          {
            const unsigned int j  = cloud_index[c];
            const double      *g  = vg.data() + 8 * c;
            const double      *h  = vh.data() + 8 * c;
            for (unsigned int p = 0; p < 2; ++p)
              for (unsigned int q = 0; q < 2; ++q)
                {
                  const unsigned int r = 4 * p + 2 * q;
                  u_new[2 * a + p] += g[r] * u[q][j] + g[r + 1] * u_old[q][j];
                  v_new[2 * a + p] += h[r] * v[q][j] + h[r + 1] * v_old[q][j];
                }
          }
    }


    PdUnboundedElastic::PdUnboundedElastic(const MPI_Comm comm)
      : disc(comm)
    {}

    void
    PdUnboundedElastic::setup(const Domain<2>                                                   &domain,
                              const LatticeParameters                                           &lattice,
                              const BondBasedModelParameters                                    &model,
                              const ElasticWaveParameters                                       &wave,
                              const ElasticTruncation                                            trunc,
                              const WaveAbcParameters                                           &prm_in,
                              const Function<2>                                                 &initial,
                              const std::function<bool(const Point<2> &, const Tensor<1, 2> &)> &keep)
    {
      check_parameter(domain.has_signed_distance(), "Geometry/Domain", "without signed distance",
                      "a box or a ball (the truncation layer needs the distance to the boundary)");
      check_parameter(wave.density > 0., "Model/Density", wave.density, "> 0");
      check_parameter(wave.damping >= 0., "Model/Damping", wave.damping, ">= 0");
      check_parameter(initial.n_components == 2, "Initial displacement", initial.n_components,
                      "2 components");
      disc.setup(domain, lattice);
      op  = std::make_unique<BondBasedOperator<2>>(disc, model);
      rho = wave.density;
      d   = wave.damping;
      const double dt_crit = op->critical_time_step(rho);
      check_parameter(wave.time_step > 0. && wave.time_step <= dt_crit, "Time stepping/Time step",
                      wave.time_step,
                      "0 < dt <= " + std::to_string(dt_crit) + " (critical step (3.8))");
      dt = wave.time_step;
      t  = 0.;
      // ElasticTruncation::absorbing follows the method parameter.
      check_parameter(trunc != ElasticTruncation::absorbing || prm_in.method == "ebf" ||
                        prm_in.method == "first order" || prm_in.method == "sponge" ||
                        prm_in.method == "pml",
                      "Absorbing boundary/Method", prm_in.method,
                      "ebf, first order, sponge or pml (elastic waves)");
      truncation = trunc != ElasticTruncation::absorbing ? trunc :
                   prm_in.method == "sponge"            ? ElasticTruncation::sponge :
                   prm_in.method == "pml"               ? ElasticTruncation::pml :
                                                          ElasticTruncation::absorbing;
      held_nodes.clear();
      fixed_nodes.clear();
      for (auto *field : {&u, &v, &a, &f})
        op->initialize(*field);
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        for (unsigned int q = 0; q < 2; ++q)
          u[q].local_element(i) = initial.value(disc.position[i], q);
      relation = std::make_unique<ElasticDispersion>(
        prm_in.dispersion == "local" ?
          ElasticDispersion::local(model.youngs_modulus, model.plane_stress, rho, d) :
          ElasticDispersion::discrete(model, lattice, rho, d));
      check_parameter(prm_in.dispersion == "local" || prm_in.dispersion == "discrete",
                      "Absorbing boundary/Dispersion relation", prm_in.dispersion,
                      "local or discrete (elastic waves)");

      WaveAbcParameters prm = prm_in;
      if (prm.cloud_radius <= 0.)
        prm.cloud_radius = lattice.delta;
      std::vector<unsigned int> nodes;
      std::vector<Tensor<1, 2>> normals;
      if (truncation != ElasticTruncation::free && truncation != ElasticTruncation::pml)
        {
          const double layer = prm.layer_thickness > 0 ? prm.layer_thickness : lattice.delta;
          std::vector<unsigned int> all_nodes;
          std::vector<Tensor<1, 2>> all_normals;
          find_absorbing_layer(disc, domain, layer, prm.cloud_radius, all_nodes, all_normals);
          for (unsigned int c = 0; c < all_nodes.size(); ++c)
            if (!keep || keep(disc.position[all_nodes[c]], all_normals[c]))
              {
                nodes.push_back(all_nodes[c]);
                normals.push_back(all_normals[c]);
              }
        }
      // The sponge (as PdUnboundedWave: sigma_max min(1, (s_in - s)/w)^p at
      // depth s; inside an overwritten or fixed layer, s_in = layer + w).
      damping.assign(disc.n_owned(), d);
      if ((truncation == ElasticTruncation::absorbing || truncation == ElasticTruncation::fixed ||
           truncation == ElasticTruncation::sponge) &&
          prm.sponge_damping > 0.)
        {
          const double s_in =
            prm.sponge_thickness +
            (truncation == ElasticTruncation::sponge ? 0. :
                                                       (prm.layer_thickness > 0 ? prm.layer_thickness : lattice.delta));
          const std::vector<double> sigma =
            sponge_profile<2>(disc, domain, prm.sponge_damping, prm.sponge_thickness, prm.sponge_exponent, s_in,
                              prm.cloud_radius, keep);
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            damping[i] += sigma[i];
        }
      else
        check_parameter(truncation != ElasticTruncation::sponge, "Absorbing boundary/Sponge damping",
                        prm.sponge_damping, "> 0 with the sponge truncation");
      // The PML (doc/design.md, session 9): the scalar PD wave PML's band
      // with the bond stiffness c omega beta V/|xi| of the linearized force
      // k e (e . (u_j - u_i)); its elongations are stretched.
      pml_band.clear();
      if (truncation == ElasticTruncation::pml)
        {
          check_parameter(!keep, "Absorbing boundary/Method", "pml",
                          "ebf or sponge when part of the boundary is a physical surface (the PML "
                          "stretches the distance to the whole truncation boundary)");
          check_parameter(op->is_linearized(), "Model/Linearized", "false",
                          "true with method pml (the stretching acts on the linearized bond force)");
          pml_band.reinit(disc, domain, op->bond_coefficients(), prm.pml_damping, prm.pml_thickness,
                          prm.pml_exponent, dt, 2);
        }
      n_layer_nodes = Utilities::MPI::sum<types::global_dof_index>(
        truncation == ElasticTruncation::pml ? pml_band.n_pml_nodes : nodes.size(), disc.get_mpi_communicator());
      if (truncation == ElasticTruncation::absorbing)
        {
          std::vector<types::global_dof_index> ids(disc.id.begin(), disc.id.end());
          abc.reinit(disc.position, ids, nodes, normals, *relation, dt, lattice.dx, prm,
                     disc.get_mpi_communicator());
        }
      else
        {
          abc = EbfElasticAbc();
          if (truncation == ElasticTruncation::fixed)
            fixed_nodes = nodes;
        }
      for (const unsigned int i : fixed_nodes)
        for (unsigned int q = 0; q < 2; ++q)
          u[q].local_element(i) = 0.;
      compute_acceleration();
      const unsigned int n_local = disc.n_owned() + disc.n_ghost();
      for (unsigned int q = 0; q < 2; ++q)
        {
          u_old[q].assign(u[q].begin(), u[q].begin() + n_local);
          v_old[q].assign(v[q].begin(), v[q].begin() + n_local);
        }
    }

    void
    PdUnboundedElastic::compute_acceleration()
    {
      for (unsigned int q = 0; q < 2; ++q)
        {
          u[q].update_ghost_values();
          v[q].update_ghost_values();
        }
      op->compute_forces(u, f);
      pml_band.apply(false, {{u[0].begin(), u[1].begin()}}, {{f[0].begin(), f[1].begin()}});
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        for (unsigned int q = 0; q < 2; ++q)
          a[q].local_element(i) = f[q].local_element(i) / rho - 2. * damping[i] * v[q].local_element(i);
    }

    void
    PdUnboundedElastic::add_precrack(const Point<2> &pa, const Point<2> &pb)
    {
      op->add_precrack(pa, pb);
      compute_acceleration();
    }

    void
    PdUnboundedElastic::set_prescribed_velocity(
      const std::function<bool(const Point<2> &)>               &region,
      const std::function<Tensor<1, 2>(const Point<2> &, double)> &velocity)
    {
      held_nodes.clear();
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (region(disc.position[i]))
          held_nodes.push_back(i);
      held_velocity = velocity;
      for (const unsigned int i : held_nodes)
        {
          const Tensor<1, 2> vi = held_velocity(disc.position[i], t);
          for (unsigned int q = 0; q < 2; ++q)
            {
              v[q].local_element(i) = vi[q];
              a[q].local_element(i) = 0.;
            }
        }
      for (unsigned int q = 0; q < 2; ++q)
        v[q].update_ghost_values();
    }

    void
    PdUnboundedElastic::advance()
    {
      using clock      = std::chrono::steady_clock;
      const auto start = clock::now();
      const auto &nodes = abc.absorbing_points();
      const bool  absorbing = truncation == ElasticTruncation::absorbing;
      if (absorbing)
        {
          // (4.166) from the levels n and n-1 (ghosts of u, v are current).
          abc.compute({{u[0].begin(), u[1].begin()}}, {{u_old[0].data(), u_old[1].data()}},
                      {{v[0].begin(), v[1].begin()}}, {{v_old[0].data(), v_old[1].data()}}, u_abc,
                      v_abc);
          for (const unsigned int j : abc.cloud_points())
            for (unsigned int q = 0; q < 2; ++q)
              {
                u_old[q][j] = u[q].begin()[j];
                v_old[q][j] = v[q].begin()[j];
              }
        }
      const auto   abc_end = clock::now();
      const double half    = 0.5 * dt;
      for (unsigned int q = 0; q < 2; ++q)
        {
          double *uu = u[q].begin(), *vv = v[q].begin();
          const double *aa = a[q].begin();
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            {
              uu[i] += dt * (vv[i] + half * aa[i]);
              vv[i] += half * aa[i];
            }
        }
      // Held nodes: u^{n+1} = u^n + dt v(t^{n+1/2}) (their a is 0, v = v(t^n)).
      for (const unsigned int i : held_nodes)
        {
          const Tensor<1, 2> vh = held_velocity(disc.position[i], t + half);
          for (unsigned int q = 0; q < 2; ++q)
            u[q].local_element(i) += dt * (vh[q] - v[q].local_element(i));
        }
      for (unsigned int c = 0; c < nodes.size(); ++c)
        for (unsigned int q = 0; q < 2; ++q)
          u[q].local_element(nodes[c]) = u_abc[2 * c + q];
      for (const unsigned int i : fixed_nodes)
        for (unsigned int q = 0; q < 2; ++q)
          u[q].local_element(i) = 0.;
      t += dt;
      for (unsigned int q = 0; q < 2; ++q)
        u[q].update_ghost_values();
      op->compute_forces(u, f);
      pml_band.apply(true, {{u[0].begin(), u[1].begin()}}, {{f[0].begin(), f[1].begin()}});
      for (unsigned int q = 0; q < 2; ++q)
        {
          double       *vv = v[q].begin(), *aa = a[q].begin();
          const double *ff = f[q].begin();
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            {
              const double scale = 1. / (1. + dt * damping[i]);
              vv[i]              = scale * (vv[i] + half * ff[i] / rho);
              aa[i]              = ff[i] / rho - 2. * damping[i] * vv[i];
            }
        }
      const auto set_start = clock::now();
      for (const unsigned int i : held_nodes)
        {
          const Tensor<1, 2> vi = held_velocity(disc.position[i], t);
          for (unsigned int q = 0; q < 2; ++q)
            {
              v[q].local_element(i) = vi[q];
              a[q].local_element(i) = 0.;
            }
        }
      for (unsigned int c = 0; c < nodes.size(); ++c)
        for (unsigned int q = 0; q < 2; ++q)
          v[q].local_element(nodes[c]) = v_abc[2 * c + q];
      for (const unsigned int i : fixed_nodes)
        for (unsigned int q = 0; q < 2; ++q)
          v[q].local_element(i) = 0.;
      for (unsigned int q = 0; q < 2; ++q)
        v[q].update_ghost_values();
      const auto end = clock::now();
      abc_seconds += std::chrono::duration<double>(abc_end - start + end - set_start).count();
      step_seconds += std::chrono::duration<double>(end - start).count();
    }

    double
    PdUnboundedElastic::one_step_spectral_radius(const unsigned int max_size, unsigned int *n_unstable)
    {
      const MPI_Comm comm = disc.get_mpi_communicator();
      check_parameter(Utilities::MPI::n_mpi_processes(comm) == 1, "MPI ranks",
                      Utilities::MPI::n_mpi_processes(comm),
                      "1 (the spectral radius check assembles the dense one-step map)");
      check_parameter(op->is_linearized(), "Model/Linearized", "false",
                      "true (the one-step map must be linear)");
      const unsigned int               n = disc.n_owned();
      const std::vector<unsigned int> &c = abc.cloud_points();
      const unsigned int               nc = truncation == ElasticTruncation::absorbing ? c.size() : 0;
      // The PML memories (bond, then node) follow u, v and the cloud levels.
      std::vector<double> &bm = pml_band.bond_memory, &nm = pml_band.node_memory;
      const unsigned int   m_pml = 4 * n + 4 * nc, m = m_pml + bm.size() + nm.size();
      check_parameter(m <= max_size, "State size of the spectral radius check", m,
                      "<= " + std::to_string(max_size) + " (dense eigenvalue problem)");
      // Entry of component q: u at q n + i, v at (2 + q) n + i, u_old at
      // 4 n + q nc + k, v_old at 4 n + (2 + q) nc + k.
      const VectorField                        u0 = u, v0 = v, a0 = a;
      const std::array<std::vector<double>, 2> uo0 = u_old, vo0 = v_old;
      const std::vector<double>                bm0 = bm, nm0 = nm;
      const double                             t0 = t, abc0 = abc_seconds, step0 = step_seconds;
      LAPACKFullMatrix<double>                 map(m, m);
      for (unsigned int col = 0; col < m; ++col)
        {
          for (unsigned int q = 0; q < 2; ++q)
            {
              for (unsigned int i = 0; i < n; ++i)
                {
                  u[q].local_element(i) = (col == q * n + i) ? 1. : 0.;
                  v[q].local_element(i) = (col == (2 + q) * n + i) ? 1. : 0.;
                }
              for (unsigned int k = 0; k < nc; ++k)
                {
                  u_old[q][c[k]] = (col == 4 * n + q * nc + k) ? 1. : 0.;
                  v_old[q][c[k]] = (col == 4 * n + (2 + q) * nc + k) ? 1. : 0.;
                }
            }
          for (unsigned int k = 0; k < bm.size(); ++k)
            bm[k] = (col == m_pml + k) ? 1. : 0.;
          for (unsigned int k = 0; k < nm.size(); ++k)
            nm[k] = (col == m_pml + bm.size() + k) ? 1. : 0.;
          compute_acceleration();
          advance();
          for (unsigned int q = 0; q < 2; ++q)
            {
              for (unsigned int i = 0; i < n; ++i)
                {
                  map(q * n + i, col)       = u[q].local_element(i);
                  map((2 + q) * n + i, col) = v[q].local_element(i);
                }
              for (unsigned int k = 0; k < nc; ++k)
                {
                  map(4 * n + q * nc + k, col)       = u_old[q][c[k]];
                  map(4 * n + (2 + q) * nc + k, col) = v_old[q][c[k]];
                }
            }
          for (unsigned int k = 0; k < bm.size(); ++k)
            map(m_pml + k, col) = bm[k];
          for (unsigned int k = 0; k < nm.size(); ++k)
            map(m_pml + bm.size() + k, col) = nm[k];
        }
      u     = u0;
      v     = v0;
      a     = a0;
      u_old = uo0;
      v_old = vo0;
      bm    = bm0;
      nm    = nm0;
      for (unsigned int q = 0; q < 2; ++q)
        {
          u[q].update_ghost_values();
          v[q].update_ghost_values();
        }
      t            = t0;
      abc_seconds  = abc0;
      step_seconds = step0;
      map.compute_eigenvalues(false, false);
      double       rho_max = 0.;
      unsigned int n_up    = 0;
      for (unsigned int i = 0; i < m; ++i)
        {
          const double mod = std::abs(map.eigenvalue(i));
          rho_max          = std::max(rho_max, mod);
          n_up += mod > 1. + 1e-8 ? 1 : 0;
        }
      if (n_unstable)
        *n_unstable = n_up;
      return rho_max;
    }

    std::array<double, 2>
    PdUnboundedElastic::energy(const std::function<bool(const Point<2> &)> &inside) const
    {
      Vector W;
      disc.initialize_vector(W);
      op->strain_energy_density(u, W);
      std::array<double, 2> e{{0., 0.}};
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (inside(disc.position[i]))
          {
            double v2 = 0.;
            for (unsigned int q = 0; q < 2; ++q)
              v2 += v[q].local_element(i) * v[q].local_element(i);
            e[0] += 0.5 * rho * v2 * disc.volume[i];
            e[1] += W.local_element(i) * disc.volume[i];
          }
      const MPI_Comm comm = disc.get_mpi_communicator();
      return {{Utilities::MPI::sum(e[0], comm), Utilities::MPI::sum(e[1], comm)}};
    }

    double
    PdUnboundedElastic::verlet_energy() const
    {
      const auto all = [](const Point<2> &) { return true; };
      const auto e   = energy(all);
      double     c   = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        for (unsigned int q = 0; q < 2; ++q)
          c += f[q].local_element(i) * f[q].local_element(i) / rho * disc.volume[i];
      return e[0] + e[1] - dt * dt / 8. * Utilities::MPI::sum(c, disc.get_mpi_communicator());
    }

    std::vector<PdUnboundedElastic::NodeState>
    PdUnboundedElastic::gather(const std::function<bool(const Point<2> &)> &inside) const
    {
      Vector phi;
      disc.initialize_vector(phi);
      op->damage(phi);
      std::vector<NodeState> local;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (inside(disc.position[i]))
          {
            NodeState s;
            s.id       = disc.id[i];
            s.position = disc.position[i];
            for (unsigned int q = 0; q < 2; ++q)
              {
                s.displacement[q] = u[q].local_element(i);
                s.velocity[q]     = v[q].local_element(i);
              }
            s.damage = phi.local_element(i);
            local.push_back(s);
          }
      // Packed as doubles for the all-gather (ids < 2^53 are exact).
      std::vector<double> packed;
      for (const auto &s : local)
        packed.insert(packed.end(), {double(s.id), s.position[0], s.position[1], s.displacement[0],
                                     s.displacement[1], s.velocity[0], s.velocity[1], s.damage});
      std::vector<NodeState> out;
      for (const auto &chunk : Utilities::MPI::all_gather(disc.get_mpi_communicator(), packed))
        for (std::size_t o = 0; o + 8 <= chunk.size(); o += 8)
          {
            NodeState s;
            s.id              = static_cast<types::global_dof_index>(chunk[o]);
            s.position        = Point<2>(chunk[o + 1], chunk[o + 2]);
            s.displacement[0] = chunk[o + 3];
            s.displacement[1] = chunk[o + 4];
            s.velocity[0]     = chunk[o + 5];
            s.velocity[1]     = chunk[o + 6];
            s.damage          = chunk[o + 7];
            out.push_back(s);
          }
      std::sort(out.begin(), out.end(),
                [](const NodeState &p, const NodeState &q) { return p.id < q.id; });
      return out;
    }

    ElasticRunHistory
    run_elastic_waves(PdUnboundedElastic                          &solver,
                      const double                                 final_time,
                      const unsigned int                           n_samples,
                      const std::function<bool(const Point<2> &)> &region)
    {
      ElasticRunHistory  h;
      const double       dt      = solver.time_step();
      const unsigned int n_steps = static_cast<unsigned int>(std::round(final_time / dt));
      const auto         all     = [](const Point<2> &) { return true; };
      const double       t0      = solver.time();
      for (unsigned int s = 0; s <= n_samples; ++s)
        {
          const unsigned int target = n_steps * s / n_samples;
          while (std::round((solver.time() - t0) / dt) < target)
            solver.advance();
          const auto e = solver.energy(region);
          const auto E = solver.energy(all);
          h.times.push_back(solver.time());
          h.kinetic.push_back(e[0]);
          h.strain.push_back(e[1]);
          h.total.push_back(E[0] + E[1]);
          h.verlet.push_back(solver.verlet_energy());
        }
      h.final_state   = solver.gather(region);
      h.stats         = solver.absorbing_boundary().statistics();
      h.n_nodes       = solver.discretization().n_global();
      h.n_layer_nodes = solver.n_layer_nodes;
      h.abc_seconds   = solver.abc_seconds;
      h.step_seconds  = solver.step_seconds;
      return h;
    }
  } // namespace Abc
} // namespace PeriDEAL
