#include <deal.II/base/quadrature_lib.h>

#include <deal.II/lac/lapack_full_matrix.h>

#include <boost/math/special_functions/bessel.hpp>

#include <perideal/abc/absorbing_layer.h>
#include <perideal/abc/ebf_cloud.h>
#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/abc/spectral_radius.h>
#include <perideal/base/exceptions.h>

#include <Eigen/Dense>

#if defined(__AVX2__) && defined(__FMA__)
#  include <immintrin.h>
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace PeriDEAL
{
  namespace Abc
  {
    double
    spectral_radius(dealii::LAPACKFullMatrix<double> &map,
                    unsigned int                     *n_unstable,
                    std::complex<double>             *dominant)
    {
      map.compute_eigenvalues(false, false);
      double       rho  = 0.;
      unsigned int n_up = 0;
      for (unsigned int i = 0; i < map.m(); ++i)
        {
          const double mod = std::abs(map.eigenvalue(i));
          if (mod > rho && dominant)
            *dominant = map.eigenvalue(i);
          rho = std::max(rho, mod);
          n_up += mod > 1. + 1e-8 ? 1 : 0;
        }
      if (n_unstable)
        *n_unstable = n_up;
      return rho;
    }

    void
    WaveAbcParameters::declare_parameters(ParameterHandler &prm)
    {
      prm.declare_entry("Number of wave numbers", "10", Patterns::Integer(1, 200),
                        "n_k: subdivisions of [-Delta k, Delta k] (n_k + 1 wave numbers, (4.98)).");
      prm.declare_entry("Wave number range", "1", Patterns::Double(0.),
                        "Delta k (4.56); 0 < Delta k <= pi/dx (4.83).");
      prm.declare_entry("Number of directions", "10", Patterns::Integer(0, 100),
                        "n_phi: subdivisions of [-Delta phi, Delta phi] (2D).");
      prm.declare_entry("Direction range", "0.785398163397448", Patterns::Double(0., M_PI / 2.),
                        "Delta phi of the mode directions (4.56).");
      prm.declare_entry("Cone angle", "0.785398163397448", Patterns::Double(0., M_PI / 2.),
                        "Delta phi of the conic extrapolation region (4.86).");
      prm.declare_entry("Cloud radius", "0", Patterns::Double(0.),
                        "d_inf (0: the horizon for PD, 2 dx for FEM).");
      prm.declare_entry("Cloud size", "0", Patterns::Integer(0, 50),
                        "n: x_i and its n nearest cone points (ties kept; the cloud radius is then the "
                        "search radius, FEM default 2 n dx); 0: all cone points within the cloud radius.");
      prm.declare_entry("Layer thickness", "0", Patterns::Double(0.),
                        "PD absorbing layer delta_L (0: the horizon).");
      prm.declare_entry("Dispersion relation", "discrete",
                        Patterns::Selection("local|nonlocal|discrete"),
                        "local (4.39), continuum nonlocal (4.47/4.51/4.90) or discrete (4.85/4.95; FEM Q1: the "
                        "stiffness row over the lumped mass or the consistent mass row).");
      prm.declare_entry("Maximum condition number", "1e12", Patterns::Double(1.),
                        "Guard on the moment matrices.");
      prm.declare_entry("Maximum updating vector norm", "2", Patterns::Double(0.),
                        "Guard on max_j |V_j| (Sect. 4.2.3).");
      prm.declare_entry("Pseudo-inverse tolerance", "0", Patterns::Double(0., 1.),
                        "Relative singular-value cutoff of M^+ (0: max(rows, cols) * machine epsilon).");
      prm.declare_entry("Pseudo-inverse regularization", "truncate", Patterns::Selection("truncate|tikhonov"),
                        "truncate (1/sigma above the tolerance, 0 below) or tikhonov (sigma/(sigma^2 + "
                        "lambda^2), lambda = tolerance * sigma_max; needs a tolerance > 0).");
      prm.declare_entry("Time levels", "2", Patterns::Integer(1, 2),
                        "Levels of the cloud data in (4.79): 2 (n and n-1, the source) or 1 (n only).");
      prm.declare_entry("Spectral radius check size", "0", Patterns::Integer(0),
                        "PD, serial runs: largest state size (2 n_nodes + 2 n_cloud_points) for which "
                        "setup computes the spectral radius of the one-step map (0: never).");
      prm.declare_entry("Thinning", "nearest", Patterns::Selection("nearest|average"),
                        "Auxiliary-grid thinning (Fig. 4.23): the nearest node (the source) or the "
                        "mean of the nodes in each auxiliary cell (filters the shortest lattice waves).");
      prm.declare_entry("Cloud points", "all", Patterns::Selection("all|interior"),
                        "PD: all points of the cone (the source) or only non-absorbing ones.");
      prm.declare_entry("Lattice modes", "none", Patterns::Selection("none|corner|zone"),
                        "Mesh-scale standing modes added to the mode set: none (the source), the "
                        "Brillouin-zone corner, or corner and face centres.");
      prm.declare_entry("Lattice mode damping", "0", Patterns::Double(0.),
                        "Extra decay rate of the lattice modes.");
      prm.declare_entry("Evanescent modes", "none", Patterns::Selection("none|outgoing"),
                        "1D, lattice (discrete) relation: the complex-k roots of Omega^2(k) = Omega^2(k_m) "
                        "decaying outward added to the modes (outgoing), or none (the source).");
      prm.declare_entry("Layer filter", "0", Patterns::Double(0., 0.25),
                        "eps of the lattice-Laplacian viscosity added to the updating vectors "
                        "(eps sum over the nearest nodes of (u_j - u_i)^n - (u_j - u_i)^{n-1}; 0: the source).");
      prm.declare_entry("Fit form", "value", Patterns::Selection("value|increment"),
                        "value (the source: V = Psi(0, dt) M^+) or increment (V = e_i + "
                        "(Psi(0, dt) - Psi(0, 0)) M^+: a truncated pseudo-inverse filters only the "
                        "change over one step).");
      prm.declare_entry("Curvature radius", "0", Patterns::Double(0.),
                        "2D: radius rho of the outgoing wave fronts at the boundary (0: plane modes, the "
                        "source); rho > 0: modes in polar coordinates about x_i - rho n with the "
                        "cylindrical amplitude sqrt(rho/r) (e.g. a disk near field centred at the source).");
      prm.declare_entry("Wake curvature radius", "0", Patterns::Double(0.),
                        "2D: curvature radius of the harmonic modes with |k| <= Wake wave number (0: Curvature radius for all).");
      prm.declare_entry("Wake wave number", "0", Patterns::Double(0.),
                        "Largest |k| of the modes that get the Wake curvature radius.");
      prm.declare_entry("Wake angle exponent", "0", Patterns::Double(),
                        "2D: p of the per-node wake radius Wake curvature radius * cos(theta)^p, theta "
                        "between the normal and the direction from the centroid of the absorbing nodes (0: one radius).");
      prm.declare_entry("Method", "ebf", Patterns::Selection("ebf|first order|sponge|pml"),
                        "The EBF extrapolation (4.82), the conventional first-order ABC (4.75), "
                        "only the damping sponge (PD: nothing overwritten, energy-stable), or the "
                        "split-field perfectly matched layer (PD).");
      prm.declare_entry("Sponge damping", "0", Patterns::Double(0.),
                        "PD: largest extra damping rate sigma_max of the sponge, u'' = L u - 2 (d + "
                        "sigma) u' (0: no sponge).");
      prm.declare_entry("Sponge thickness", "0", Patterns::Double(0.),
                        "PD: sponge width w inside the overwritten layer (method sponge: from the "
                        "boundary); > 0 when the sponge damping is > 0.");
      prm.declare_entry("Sponge exponent", "2", Patterns::Double(0.),
                        "PD: p of the profile sigma = sigma_max min(1, (s_in - s)/w)^p over the depth s.");
      prm.declare_entry("PML damping", "0", Patterns::Double(0.),
                        "PD scalar and elastic waves, method pml: largest damping rate sigma_max of the PML (> 0).");
      prm.declare_entry("PML thickness", "0", Patterns::Double(0.),
                        "PD, method pml: PML width w, the outermost part of the near field (>= 2 dx).");
      prm.declare_entry("PML exponent", "2", Patterns::Double(1.),
                        "PD, method pml: p of the profile sigma = sigma_max (rho/w)^p over the distance "
                        "rho into the PML.");
      prm.declare_entry("Maximum spectral radius", "1.00000001", Patterns::Double(1.),
                        "Setup throws ParameterError if the checked spectral radius exceeds this.");
      prm.declare_entry("Share updating vectors", "true", Patterns::Bool(),
                        "Store one set of updating vectors per class of congruent clouds (local "
                        "frames, up to a reflection) instead of one per absorbing node: equal to "
                        "round-off, fewer bytes per step.");
    }

    void
    WaveAbcParameters::parse_parameters(ParameterHandler &prm)
    {
      n_wave_numbers       = prm.get_integer("Number of wave numbers");
      wave_number_range    = prm.get_double("Wave number range");
      n_directions         = prm.get_integer("Number of directions");
      direction_range      = prm.get_double("Direction range");
      cone_angle           = prm.get_double("Cone angle");
      cloud_radius         = prm.get_double("Cloud radius");
      cloud_size           = prm.get_integer("Cloud size");
      layer_thickness      = prm.get_double("Layer thickness");
      dispersion           = prm.get("Dispersion relation");
      max_condition_number = prm.get_double("Maximum condition number");
      max_update_norm      = prm.get_double("Maximum updating vector norm");
      pseudo_inverse_tolerance = prm.get_double("Pseudo-inverse tolerance");
      pseudo_inverse_regularization = prm.get("Pseudo-inverse regularization");
      spectral_check_size      = prm.get_integer("Spectral radius check size");
      n_time_levels            = prm.get_integer("Time levels");
      max_spectral_radius      = prm.get_double("Maximum spectral radius");
      cloud_points             = prm.get("Cloud points");
      thinning                 = prm.get("Thinning");
      lattice_modes            = prm.get("Lattice modes");
      lattice_mode_damping     = prm.get_double("Lattice mode damping");
      evanescent_modes         = prm.get("Evanescent modes");
      layer_filter             = prm.get_double("Layer filter");
      fit_form                 = prm.get("Fit form");
      curvature_radius         = prm.get_double("Curvature radius");
      wake_curvature_radius    = prm.get_double("Wake curvature radius");
      wake_wave_number         = prm.get_double("Wake wave number");
      wake_angle_exponent      = prm.get_double("Wake angle exponent");
      method                   = prm.get("Method");
      sponge_damping           = prm.get_double("Sponge damping");
      sponge_thickness         = prm.get_double("Sponge thickness");
      sponge_exponent          = prm.get_double("Sponge exponent");
      pml_damping              = prm.get_double("PML damping");
      pml_thickness            = prm.get_double("PML thickness");
      pml_exponent             = prm.get_double("PML exponent");
      share_updating_vectors   = prm.get_bool("Share updating vectors");
    }


    template <int dim>
    WaveDispersion<dim>
    WaveDispersion<dim>::local(const double chi, const double damping)
    {
      WaveDispersion<dim> w;
      w.name    = "local";
      w.damping = damping;
      w.omega2  = [chi](const Tensor<1, dim> &k) { return chi * chi * (k * k); };
      return w;
    }

    template <int dim>
    WaveDispersion<dim>
    WaveDispersion<dim>::nonlocal(const ScalarKernel &kernel, const double damping)
    {
      static_assert(dim <= 2, "1D and 2D only");
      WaveDispersion<dim> w;
      w.name    = "nonlocal";
      w.damping = damping;
      // Radial composite Gauss rule on [0, delta] (8 panels of 10 points):
      // the integrand k(r) r^(dim-1) A(|k| r) with A = O((kr)^2) is smooth.
      const QGauss<1>     gauss(10);
      std::vector<double> r, wq;
      const unsigned int  n_panels = 8;
      for (unsigned int p = 0; p < n_panels; ++p)
        for (unsigned int q = 0; q < gauss.size(); ++q)
          {
            r.push_back((p + gauss.point(q)[0]) * kernel.delta / n_panels);
            wq.push_back(gauss.weight(q) * kernel.delta / n_panels);
          }
      w.omega2 = [kernel, r, wq](const Tensor<1, dim> &kv) {
        const double k = kv.norm();
        double       s = 0.;
        for (unsigned int q = 0; q < r.size(); ++q)
          {
            const double x = k * r[q];
            // Angular integral of 1 - cos(k r n.e) over the unit sphere.
            const double angular =
              dim == 1 ? 2. * (1. - std::cos(x)) :
                         (std::abs(x) < 1e-4 ? 2. * M_PI * x * x / 4. :
                                               2. * M_PI * (1. - boost::math::cyl_bessel_j(0, x)));
            s += wq[q] * kernel(r[q]) * std::pow(r[q], double(dim) - 1.) * angular;
          }
        return s;
      };
      return w;
    }

    template <int dim>
    WaveDispersion<dim>
    WaveDispersion<dim>::stencil(const std::vector<Tensor<1, dim>> &offsets,
                                 const std::vector<double>         &weights,
                                 const double                       damping,
                                 const std::string                 &name,
                                 const double                       mass_diagonal,
                                 const std::vector<Tensor<1, dim>> &mass_offsets,
                                 const std::vector<double>         &mass_weights)
    {
      AssertDimension(offsets.size(), weights.size());
      AssertDimension(mass_offsets.size(), mass_weights.size());
      WaveDispersion<dim> w;
      w.name    = name;
      w.damping = damping;
      w.omega2  = [offsets, weights, mass_diagonal, mass_offsets, mass_weights](const Tensor<1, dim> &k) {
        double s = 0., m = mass_diagonal;
        for (unsigned int j = 0; j < offsets.size(); ++j)
          s += weights[j] * (1. - std::cos(k * offsets[j]));
        for (unsigned int j = 0; j < mass_offsets.size(); ++j)
          m += mass_weights[j] * std::cos(k * mass_offsets[j]);
        return s / m;
      };
      return w;
    }

    template <int dim>
    WaveDispersion<dim>
    WaveDispersion<dim>::discrete(const ScalarKernel &kernel,
                                  const double        dx,
                                  const bool          partial_volume,
                                  const double        damping)
    {
      // The lattice family of the origin exactly as the Discretization builds
      // it (beta by Discretization::volume_factor, kernel at min(r, delta)).
      const int                   m = static_cast<int>(std::ceil(kernel.delta / dx + 0.5)) + 1;
      std::vector<Tensor<1, dim>> offsets;
      std::vector<double>         weights;
      std::array<int, dim>        l;
      const unsigned int          n = 2 * m + 1;
      unsigned int                total = 1;
      for (unsigned int d = 0; d < dim; ++d)
        total *= n;
      for (unsigned int c = 0; c < total; ++c)
        {
          unsigned int   cc = c;
          Tensor<1, dim> xi;
          for (unsigned int d = 0; d < dim; ++d, cc /= n)
            {
              l[d]  = int(cc % n) - m;
              xi[d] = l[d] * dx;
            }
          const double r = xi.norm();
          if (r == 0.)
            continue;
          const double beta =
            Discretization<dim>::volume_factor(r, kernel.delta, dx, partial_volume);
          if (beta <= 0.)
            continue;
          offsets.push_back(xi);
          weights.push_back(kernel(std::min(r, kernel.delta)) * beta * std::pow(dx, dim));
        }
      return stencil(offsets, weights, damping, "discrete");
    }

    template <int dim>
    std::complex<double>
    WaveDispersion<dim>::frequency(const double k, const Tensor<1, dim> &n) const
    {
      const std::complex<double> root =
        std::sqrt(std::complex<double>(omega2(std::abs(k) * n) - damping * damping, 0.));
      return k < 0 ? -root : root;
    }


    template <int dim>
    Tensor<2, dim>
    EbfWaveAbc<dim>::local_frame(const Tensor<1, dim> &n_in)
    {
      const Tensor<1, dim> n = n_in / n_in.norm();
      Tensor<2, dim>       R;
      if (dim == 1)
        R[0][0] = n[0] > 0 ? 1. : -1.;
      else
        {
          // Rows: the normal (x bar) and the tangent (y bar), Fig. 4.20.
          R[0][0] = n[0];
          R[0][1] = n[1];
          R[1][0] = -n[1];
          R[1][1] = n[0];
        }
      return R;
    }

    namespace
    {
      using CMatrix = Eigen::MatrixXcd;
      using CRow    = Eigen::RowVectorXcd;

      /** max_j |Re V_j| and condition number of one moment matrix fit. */
      struct Fit
      {
        Eigen::RowVectorXd V;
        double             cond = 0., vmax = 0.;
      };

      Fit
      fit(const CMatrix &M, const CRow &psi, const double tolerance, const bool tikhonov = false)
      {
        const PseudoInverseFit p = pseudo_inverse_fit(M, CMatrix(psi), tolerance, tikhonov);
        Fit                    f;
        f.V    = p.V.row(0);
        f.cond = p.condition_number;
        f.vmax = p.max_norm;
        return f;
      }

      /**
       * 1D lattice relation Omega^2(k) = sum_{j=1}^J a_j (1 - cos(k j dx)):
       * the coefficients a_j recovered from samples of @p omega2 (the
       * smallest J <= 16 that reproduces it at off-grid wave numbers to
       * 1e-10 relative); empty if it is no such trigonometric polynomial.
       */
      std::vector<double>
      lattice_coefficients(const std::function<double(double)> &omega2, const double dx)
      {
        const double kmax = M_PI / dx;
        double       scale = 0.;
        for (unsigned int q = 1; q <= 64; ++q)
          scale = std::max(scale, std::abs(omega2(kmax * q / 64.)));
        for (unsigned int J = 1; J <= 64; ++J)
          {
            Eigen::MatrixXd A(J, J);
            Eigen::VectorXd b(J);
            for (unsigned int q = 0; q < J; ++q)
              {
                const double kq = kmax * (q + 1.) / J;
                b[q]            = omega2(kq);
                for (unsigned int j = 0; j < J; ++j)
                  A(q, j) = 1. - std::cos(kq * (j + 1.) * dx);
              }
            const Eigen::VectorXd a  = A.colPivHouseholderQr().solve(b);
            double                err = 0.;
            for (const double t : {0.137, 0.291, 0.4433, 0.618, 0.777, 0.9137})
              {
                double s = 0.;
                for (unsigned int j = 0; j < J; ++j)
                  s += a[j] * (1. - std::cos(t * kmax * (j + 1.) * dx));
                err = std::max(err, std::abs(s - omega2(t * kmax)));
              }
            if (err <= 1e-10 * scale)
              return std::vector<double>(a.data(), a.data() + J);
          }
        return {};
      }

      /**
       * The roots z = exp(i k dx) of sum_j a_j (1 - (z^j + z^-j)/2) = W2
       * inside the unit circle (|z| < 1 - 1e-8: decaying outward), as
       * complex wave numbers k = -i log(z) / dx.
       */
      std::vector<std::complex<double>>
      evanescent_wave_numbers(const std::vector<double> &a, const double W2, const double dx)
      {
        // z^J times the relation: degree 2J polynomial, coefficients c_p of z^p.
        const unsigned int  J = a.size();
        std::vector<double> c(2 * J + 1, 0.);
        c[J] = -W2;
        for (unsigned int j = 1; j <= J; ++j)
          {
            c[J] += a[j - 1];
            c[J + j] -= 0.5 * a[j - 1];
            c[J - j] -= 0.5 * a[j - 1];
          }
        // Companion matrix of the monic polynomial (leading c_{2J} = -a_J/2 != 0).
        const unsigned int n = 2 * J;
        Eigen::MatrixXd    C = Eigen::MatrixXd::Zero(n, n);
        for (unsigned int p = 1; p < n; ++p)
          C(p, p - 1) = 1.;
        for (unsigned int p = 0; p < n; ++p)
          C(p, n - 1) = -c[p] / c[n];
        const Eigen::EigenSolver<Eigen::MatrixXd> es(C, false);
        std::vector<std::complex<double>>         k;
        for (Eigen::Index p = 0; p < es.eigenvalues().size(); ++p)
          {
            const std::complex<double> z = es.eigenvalues()[p];
            const double               r = std::abs(z);
            if (r < 1. - 1e-8)
              k.push_back(-std::complex<double>(0., 1.) * std::log(z) / dx);
          }
        return k;
      }
    } // namespace

    template <int dim>
    void
    EbfWaveAbc<dim>::reinit(const std::vector<Point<dim>>              &points,
                            const std::vector<types::global_dof_index> &ids,
                            const std::vector<unsigned int>            &absorbing_in,
                            const std::vector<Tensor<1, dim>>          &normals,
                            const WaveDispersion<dim>                  &dispersion,
                            const double                                dt,
                            const double                                dx,
                            const WaveAbcParameters                    &prm,
                            const MPI_Comm                              comm,
                            const std::vector<bool>                    &excluded)
    {
      AssertDimension(points.size(), ids.size());
      AssertDimension(absorbing_in.size(), normals.size());
      check_parameter(prm.n_time_levels == 1 || prm.n_time_levels == 2, "Absorbing boundary/Time levels",
                      prm.n_time_levels, "1 or 2");
      check_parameter(prm.wave_number_range > 0. && prm.wave_number_range <= M_PI / dx * (1. + 1e-12),
                      "Absorbing boundary/Wave number range", prm.wave_number_range,
                      "0 < Delta k <= pi/dx = " + std::to_string(M_PI / dx) + " (4.83)");
      check_parameter(prm.cloud_radius > 0., "Absorbing boundary/Cloud radius", prm.cloud_radius,
                      "> 0");
      check_parameter(prm.cloud_size <= 50, "Absorbing boundary/Cloud size", prm.cloud_size,
                      "0 (the cloud radius) or 1 .. 50");
      check_parameter(prm.curvature_radius == 0. || prm.curvature_radius > prm.cloud_radius,
                      "Absorbing boundary/Curvature radius", prm.curvature_radius,
                      "0 or > the cloud radius " + std::to_string(prm.cloud_radius));
      check_parameter(prm.wake_curvature_radius == 0. || prm.wake_curvature_radius > prm.cloud_radius,
                      "Absorbing boundary/Wake curvature radius", prm.wake_curvature_radius,
                      "0 or > the cloud radius " + std::to_string(prm.cloud_radius));
      check_parameter(prm.wake_angle_exponent == 0. || (dim == 2 && prm.wake_curvature_radius > 0.),
                      "Absorbing boundary/Wake angle exponent", prm.wake_angle_exponent,
                      "0 unless 2D with a Wake curvature radius > 0");
      // Centroid of the absorbing nodes (all ranks) for the per-node wake radius.
      Point<dim> wake_centre;
      if (prm.wake_angle_exponent != 0.)
        {
          std::vector<double> sum(dim + 1, 0.);
          for (const unsigned int i : absorbing_in)
            {
              for (unsigned int d = 0; d < dim; ++d)
                sum[d] += points[i][d];
              sum[dim] += 1.;
            }
          for (double &x : sum)
            x = Utilities::MPI::sum(x, comm);
          for (unsigned int d = 0; d < dim; ++d)
            wake_centre[d] = sum[d] / std::max(sum[dim], 1.);
        }
      absorbing = absorbing_in;
      cloud_start.assign(1, 0);
      cloud_index.clear();
      // Each node's own coefficients per cloud entry (V_G, V_H of levels n
      // and n-1); store_updating_vectors() keeps one set per class.
      std::vector<double> vg_now, vg_old, vh_now, vh_old;
      std::vector<std::vector<std::array<double, dim + 3>>> node_modes(absorbing.size());
      info.clear();
      stats = WaveCloudStatistics();

      // Mode parameters (4.56), (4.98): k_m and phi_l in the local frame.
      std::vector<double> k, phi;
      for (unsigned int m = 0; m <= prm.n_wave_numbers; ++m)
        k.push_back(prm.wave_number_range * (-1. + 2. * m / prm.n_wave_numbers));
      if (dim == 1 || prm.n_directions == 0)
        phi.push_back(0.);
      else
        for (unsigned int l = 0; l <= prm.n_directions; ++l)
          phi.push_back(prm.direction_range * (-1. + 2. * l / prm.n_directions));
      const unsigned int n_modes = k.size() * phi.size();
      stats.n_modes              = n_modes;
      // Zone-boundary wave vectors of the near-field lattice (global frame):
      // corner (pi/dx, ..., pi/dx) and the face centres (pi/dx e_d).
      std::vector<Tensor<1, dim>> lattice_wave_vectors;
      if (prm.lattice_modes == "corner" || prm.lattice_modes == "zone")
        {
          Tensor<1, dim> K;
          for (unsigned int d = 0; d < dim; ++d)
            K[d] = M_PI / dx;
          lattice_wave_vectors.push_back(K);
        }
      if (prm.lattice_modes == "zone" && dim > 1)
        for (unsigned int d = 0; d < dim; ++d)
          {
            Tensor<1, dim> K;
            K[d] = M_PI / dx;
            lattice_wave_vectors.push_back(K);
          }

      const double r = prm.cloud_radius;
      std::map<std::array<long, dim>, std::vector<unsigned int>> bins;
      // Bins slightly wider than d_inf, so that points at distance d_inf up
      // to round-off are in the neighbouring bins.
      const double w      = r * (1. + 1e-6);
      const auto   bin_of = [w](const Point<dim> &p) {
        std::array<long, dim> b;
        for (unsigned int d = 0; d < dim; ++d)
          b[d] = static_cast<long>(std::floor(p[d] / w));
        return b;
      };
      for (unsigned int i = 0; i < points.size(); ++i)
        bins[bin_of(points[i])].push_back(i);
      // (4.86): pi/2 + Delta phi < arg(x bar) < 3 pi/2 - Delta phi, i.e.
      // x bar < 0 and |y bar| < cot(Delta phi) |x bar|.
      const double cone_slope = 1. / std::tan(std::max(prm.cone_angle, 1e-12));

      // Long-wave speed of the relation (first-order ABC).
      Tensor<1, dim> e_long;
      e_long[0]        = 1e-4;
      const double chi = std::sqrt(dispersion.symbol(e_long)) / 1e-4;
      check_parameter(prm.method == "ebf" || prm.method == "first order", "Absorbing boundary/Method",
                      prm.method, "ebf or first order");
      check_parameter(prm.evanescent_modes == "none" || prm.evanescent_modes == "outgoing",
                      "Absorbing boundary/Evanescent modes", prm.evanescent_modes, "none or outgoing");
      std::vector<double> lattice;
      if (prm.evanescent_modes != "none" && prm.method == "ebf")
        {
          check_parameter(dim == 1, "Absorbing boundary/Evanescent modes", prm.evanescent_modes, "none in 2D");
          lattice = lattice_coefficients(
            [&dispersion](const double kk) {
              Tensor<1, dim> kv;
              kv[0] = kk;
              return dispersion.symbol(kv);
            },
            dx);
          check_parameter(lattice.size() >= 2, "Absorbing boundary/Evanescent modes", prm.evanescent_modes,
                          "none unless the dispersion relation is a lattice relation with >= 2 neighbours (" +
                            dispersion.name + ")");
        }
      double       max_cond = 0., max_norm = 0.;
      unsigned int min_size = std::numeric_limits<unsigned int>::max(), max_size = 0;
      unsigned int n_thinned = 0, max_stride = 1;
      for (unsigned int a = 0; a < absorbing.size(); ++a)
        {
          const unsigned int   i  = absorbing[a];
          const Point<dim>    &xi = points[i];
          const Tensor<2, dim> R  = local_frame(normals[a]);
          // Global modal directions n_l = R^T (cos phi_l, sin phi_l).
          std::vector<Tensor<1, dim>> dir_local(phi.size()), dir_global(phi.size());
          for (unsigned int l = 0; l < phi.size(); ++l)
            {
              dir_local[l][0] = std::cos(phi[l]);
              if (dim == 2)
                dir_local[l][dim - 1] = std::sin(phi[l]);
              dir_global[l] = transpose(R) * dir_local[l];
            }
          // Every mode: wave vector in the local frame, complex frequency and
          // decay rate; psi = exp(-decay t + i K.x bar - i omega t).
          std::vector<Tensor<1, dim>>       kvec;
          std::vector<std::complex<double>> omega;
          std::vector<double>               decay;
          for (unsigned int l = 0; l < phi.size(); ++l)
            for (unsigned int m = 0; m < k.size(); ++m)
              {
                kvec.push_back(k[m] * dir_local[l]);
                omega.push_back(dispersion.frequency(k[m], dir_global[l]));
                decay.push_back(dispersion.damping);
              }
          // Lattice (mesh-scale) modes: standing waves exp(i K.x) cos(omega t)
          // with K on the Brillouin-zone boundary (global frame), omega from
          // the dispersion relation, decaying by the extra rate.
          for (const auto &K : lattice_wave_vectors)
            {
              const double w2 = dispersion.symbol(K) - dispersion.damping * dispersion.damping;
              const std::complex<double> w = std::sqrt(std::complex<double>(w2, 0.));
              for (const double sgn : {1., -1.})
                {
                  kvec.push_back(R * K);
                  omega.push_back(sgn * w);
                  decay.push_back(dispersion.damping + prm.lattice_mode_damping);
                  kvec.push_back(-(R * K));
                  omega.push_back(-sgn * std::conj(w));
                  decay.push_back(dispersion.damping + prm.lattice_mode_damping);
                }
            }
          // Evanescent lattice modes (1D): complex k = kr + i kappa at the
          // frequency of each k_m > 0, exp(i kr x bar - kappa x bar), and
          // the conjugates.
          std::vector<double> kappa(kvec.size(), 0.);
          if (dim == 1 && !lattice.empty())
            for (unsigned int m = 0; m < k.size(); ++m)
              if (k[m] > 0.)
                {
                  Tensor<1, dim> km;
                  km[0] = k[m];
                  const std::complex<double> w = dispersion.frequency(k[m], dir_global[0]);
                  for (const auto &kc : evanescent_wave_numbers(lattice, dispersion.symbol(km), dx))
                    for (const double sgn : {1., -1.})
                      {
                        Tensor<1, dim> kr;
                        kr[0] = sgn * kc.real();
                        kvec.push_back(kr);
                        omega.push_back(sgn > 0. ? w : -std::conj(w));
                        decay.push_back(dispersion.damping);
                        kappa.push_back(kc.imag());
                      }
                }
          const unsigned int n_all = kvec.size();
          for (unsigned int c = 0; c < n_all; ++c)
            {
              std::array<double, dim + 3> m;
              for (unsigned int d = 0; d < dim; ++d)
                m[d] = kvec[c][d];
              m[dim]     = omega[c].real();
              m[dim + 1] = omega[c].imag();
              m[dim + 2] = decay[c];
              node_modes[a].push_back(m);
              if (kappa[c] != 0.)
                {
                  // The class key of store_updating_vectors() must see kappa.
                  std::array<double, dim + 3> e{};
                  e[0] = kappa[c];
                  node_modes[a].push_back(e);
                }
            }
          // Curved wave fronts (curvature_radius rho > 0, 2D): the local
          // coordinates become s = (r - rho, rho theta) about the centre
          // x_i - rho n, with the cylindrical amplitude sqrt(rho / r).
          const double rho_all = dim == 2 ? prm.curvature_radius : 0.;
          // Wake curvature: the harmonic modes with |k| <= the wake wave
          // number get the radius wake_curvature_radius instead (empty: off).
          double rho_wake = prm.wake_curvature_radius;
          if (prm.wake_angle_exponent != 0.)
            {
              // cos theta between the normal and the direction from the centroid.
              const Tensor<1, dim> from_c    = xi - wake_centre;
              const double         cos_theta = from_c.norm() > 0. ?
                                                 (normals[a] * from_c) / (normals[a].norm() * from_c.norm()) :
                                                 1.;
              rho_wake = cos_theta > 0. ? prm.wake_curvature_radius * std::pow(cos_theta, prm.wake_angle_exponent) : 0.;
              check_parameter(rho_wake > prm.cloud_radius, "Absorbing boundary/Wake angle exponent",
                              prm.wake_angle_exponent,
                              "a value with Wake curvature radius * cos(theta)^p > the cloud radius at absorbing node " +
                                std::to_string(ids[i]) + " (cos theta = " + std::to_string(cos_theta) + ")");
              // The class key of store_updating_vectors() must tell the radii apart.
              std::array<double, dim + 3> m{};
              m[0] = rho_wake;
              node_modes[a].push_back(m);
            }
          std::vector<bool> low_k;
          if (dim == 2 && prm.wake_curvature_radius > 0.)
            for (unsigned int c = 0; c < n_all; ++c)
              low_k.push_back(c < n_modes && kvec[c].norm() <= prm.wake_wave_number * (1. + 1e-12) + 1e-14);
          const auto   mode = [&](const Tensor<1, dim> &xbar, const double time, const unsigned int c) {
            const std::complex<double> I(0., 1.);
            Tensor<1, dim>             s         = xbar;
            double                     amplitude = 1.;
            const double               rho       = c < low_k.size() && low_k[c] ? rho_wake : rho_all;
            if (rho > 0.)
              {
                Tensor<1, dim> from_centre = xbar;
                from_centre[0] += rho;
                const double radius = from_centre.norm();
                s[0]                = radius - rho;
                s[dim - 1]          = rho * std::atan2(from_centre[dim - 1], from_centre[0]);
                amplitude           = std::sqrt(rho / radius);
              }
            return amplitude * std::exp(-decay[c] * time - kappa[c] * s[0] + I * (kvec[c] * s) - I * omega[c] * time);
          };
          const auto mode_rate = [&](const unsigned int c) {
            return -decay[c] - std::complex<double>(0., 1.) * omega[c];
          };

          // Candidates: x_i and the points of the cone within d_inf.
          std::vector<std::pair<unsigned int, Tensor<1, dim>>> cone;
          cone.emplace_back(i, Tensor<1, dim>());
          const auto         b0 = bin_of(xi);
          const unsigned int n_neighbour_bins = dim == 1 ? 3 : 9;
          for (unsigned int nb = 0; nb < n_neighbour_bins; ++nb)
            {
              auto         b = b0;
              unsigned int c = nb;
              for (unsigned int d = 0; d < dim; ++d, c /= 3)
                b[d] += long(c % 3) - 1;
              const auto it = bins.find(b);
              if (it == bins.end())
                continue;
              for (const unsigned int j : it->second)
                {
                  if (j == i || xi.distance(points[j]) > r * (1. + 1e-10) ||
                      (!excluded.empty() && excluded[j]))
                    continue;
                  const Tensor<1, dim> xbar = R * (points[j] - xi);
                  const double         lat  = dim == 2 ? std::abs(xbar[dim - 1]) : 0.;
                  if (xbar[0] < -1e-10 * dx && lat < cone_slope * (-xbar[0]) * (1. - 1e-10))
                    cone.emplace_back(j, xbar);
                }
            }
          std::sort(cone.begin() + 1, cone.end(), [&ids](const auto &p, const auto &q) {
            return ids[p.first] < ids[q.first];
          });

          if (prm.method == "first order")
            {
              // (4.75) by forward Euler: u^{n+1} = (1 - d dt) u^n - chi dt du/dn,
              // du/dn (= d/dx bar) from a linear least-squares fit over x_i
              // and the cone points within min(d_inf, 2 dx) (upwind).
              std::vector<unsigned int> sel{0};
              for (unsigned int c = 1; c < cone.size(); ++c)
                if (cone[c].second.norm() <= std::min(r, 2. * dx) * (1. + 1e-10))
                  sel.push_back(c);
              Eigen::MatrixXd A(sel.size(), dim + 1);
              for (unsigned int q = 0; q < sel.size(); ++q)
                {
                  A(q, 0) = 1.;
                  for (unsigned int d = 0; d < dim; ++d)
                    A(q, d + 1) = cone[sel[q]].second[d];
                }
              const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(A);
              check_parameter(cod.rank() == dim + 1, "Absorbing boundary/Cloud radius", r,
                              "a radius whose cone behind absorbing node " + std::to_string(ids[i]) +
                                " holds enough points for a linear fit (first-order ABC)");
              const Eigen::MatrixXd P = cod.pseudoInverse();
              WaveCloudInfo         ci;
              for (unsigned int q = 0; q < sel.size(); ++q)
                {
                  const double c = -dt * chi * P(1, q) + (q == 0 ? 1. - dt * dispersion.damping : 0.);
                  cloud_index.push_back(cone[sel[q]].first);
                  vg_now.push_back(c);
                  vg_old.push_back(0.);
                  vh_now.push_back(c);
                  vh_old.push_back(0.);
                  ci.vmax_g = ci.vmax_h = std::max(ci.vmax_g, std::abs(c));
                  ci.row_sum_g += std::abs(c);
                }
              cloud_start.push_back(cloud_index.size());
              info.push_back(ci);
              max_norm = std::max(max_norm, ci.vmax_g);
              min_size = std::min<unsigned int>(min_size, sel.size());
              max_size = std::max<unsigned int>(max_size, sel.size());
              continue;
            }

          // Cloud size n > 0 (session 19): x_i and its n nearest cone points.
          if (prm.cloud_size > 0)
            cone = nearest_cloud_points<dim>(cone, prm.cloud_size, ids, dx, r);
          std::ostringstream name;
          name << "absorbing node " << ids[i] << " at (" << xi << ")";
          Fit          fg, fh;
          bool         ok = false;
          unsigned int stride = 1;
          std::vector<std::pair<unsigned int, Tensor<1, dim>>> cloud;
          // Per cloud entry: the cone candidates it stands for and their
          // weights (one with weight 1, or a block average, see below).
          std::vector<std::vector<std::pair<unsigned int, double>>> members;
          const bool average = prm.thinning == "average";
          check_parameter(prm.fit_form == "value" || prm.fit_form == "increment", "Absorbing boundary/Fit form",
                          prm.fit_form, "value or increment");
          const bool increment = prm.fit_form == "increment";
          check_parameter(prm.pseudo_inverse_regularization == "truncate" ||
                            (prm.pseudo_inverse_regularization == "tikhonov" && prm.pseudo_inverse_tolerance > 0.),
                          "Absorbing boundary/Pseudo-inverse regularization", prm.pseudo_inverse_regularization,
                          "truncate, or tikhonov with a Pseudo-inverse tolerance > 0");
          const bool tikhonov = prm.pseudo_inverse_regularization == "tikhonov";
          for (; stride <= 8 && !ok; ++stride)
            {
              // Auxiliary grid of spacing stride * dx in the local frame
              // (Fig. 4.23); keep the candidate nearest to each auxiliary node
              // ("nearest", the source) or the mean of the candidates in its
              // block |x bar - g|_inf < stride dx / 2 ("average"): sampling
              // every stride-th node aliases the shortest lattice waves onto
              // smooth ones, the block mean filters them out.
              cloud.assign(1, cone[0]);
              members.assign(1, {{0u, 1.}});
              if (stride == 1)
                {
                  cloud = cone;
                  members.clear();
                  for (unsigned int c = 0; c < cone.size(); ++c)
                    members.push_back({{c, 1.}});
                }
              else
                {
                  std::set<unsigned int> taken{0};
                  const double           hs = stride * dx;
                  const int              na = int(std::floor(r / hs + 1e-9));
                  std::vector<std::pair<types::global_dof_index, std::size_t>> order;
                  std::vector<std::pair<unsigned int, Tensor<1, dim>>>           entries;
                  std::vector<std::vector<std::pair<unsigned int, double>>>     groups;
                  for (int ax = 1; ax <= na; ++ax)
                    for (int ay = (dim == 2 ? -na : 0); ay <= (dim == 2 ? na : 0); ++ay)
                      {
                        Tensor<1, dim> g;
                        g[0] = -ax * hs;
                        if (dim == 2)
                          g[dim - 1] = ay * hs;
                        if (g.norm() > r * (1. + 1e-10) ||
                            (dim == 2 && std::abs(g[dim - 1]) >= cone_slope * ax * hs))
                          continue;
                        unsigned int best = 0;
                        double       dist = std::numeric_limits<double>::max();
                        std::vector<unsigned int> block;
                        for (unsigned int c = 1; c < cone.size(); ++c)
                          {
                            const Tensor<1, dim> off = cone[c].second - g;
                            const double         dd  = off.norm();
                            if (dd < dist - 1e-12 * dx)
                              {
                                dist = dd;
                                best = c;
                              }
                            double inf = 0.;
                            for (unsigned int q = 0; q < dim; ++q)
                              inf = std::max(inf, std::abs(off[q]));
                            if (inf < 0.5 * hs * (1. - 1e-10))
                              block.push_back(c);
                          }
                        if (best == 0 || dist >= 0.5 * hs || !taken.insert(best).second)
                          continue;
                        std::vector<std::pair<unsigned int, double>> group;
                        if (average && !block.empty())
                          for (const unsigned int c : block)
                            group.emplace_back(c, 1. / block.size());
                        else
                          group.emplace_back(best, 1.);
                        order.emplace_back(ids[cone[best].first], entries.size());
                        entries.push_back(cone[best]);
                        groups.push_back(group);
                      }
                  // Rank-independent order: by the global id of the nearest candidate.
                  std::sort(order.begin(), order.end());
                  for (const auto &o : order)
                    {
                      cloud.push_back(entries[o.second]);
                      members.push_back(groups[o.second]);
                    }
                }
              if (cloud.size() < 2)
                break;
              // Moment matrices (4.79): rows (x_j, t = 0) and (x_j, t = -dt)
              // (block means of the modes for averaged entries).
              CMatrix MG(2 * cloud.size(), n_all), MH(2 * cloud.size(), n_all);
              CRow    psi_g(n_all), psi_h(n_all);
              for (unsigned int c = 0; c < n_all; ++c)
                {
                  psi_g[c] = mode(Tensor<1, dim>(), dt, c);
                  psi_h[c] = mode_rate(c) * psi_g[c];
                  if (increment)
                    {
                      psi_g[c] -= mode(Tensor<1, dim>(), 0., c);
                      psi_h[c] -= mode_rate(c) * mode(Tensor<1, dim>(), 0., c);
                    }
                  for (unsigned int j = 0; j < cloud.size(); ++j)
                    for (unsigned int s = 0; s < 2; ++s)
                      {
                        // One time level: the rows of level n-1 vanish
                        // (their updating coefficients become 0).
                        std::complex<double> value = 0.;
                        if (s < prm.n_time_levels)
                          for (const auto &q : members[j])
                            value += q.second * mode(cone[q.first].second, -double(s) * dt, c);
                        MG(2 * j + s, c) = value;
                        MH(2 * j + s, c) = mode_rate(c) * MG(2 * j + s, c);
                      }
                }
              fg = fit(MG, psi_g, prm.pseudo_inverse_tolerance, tikhonov);
              fh = fit(MH, psi_h, prm.pseudo_inverse_tolerance, tikhonov);
              if (increment)
                {
                  // + e_i: cloud[0] = x_i, row 0 = level n.
                  fg.V[0] += 1.;
                  fh.V[0] += 1.;
                  fg.vmax = fg.V.cwiseAbs().maxCoeff();
                  fh.vmax = fh.V.cwiseAbs().maxCoeff();
                }
              ok = fg.cond <= prm.max_condition_number && fh.cond <= prm.max_condition_number &&
                   fg.vmax <= prm.max_update_norm && fh.vmax <= prm.max_update_norm;
            }
          --stride;
          if (!ok)
            {
              std::ostringstream v;
              v << "condition numbers " << fg.cond << " (M_G), " << fh.cond << " (M_H), max |V_G| "
                << fg.vmax << ", max |V_H| " << fh.vmax << " for the " << name.str() << " ("
                << cloud.size() << " cloud points at the last thinning stride " << stride << ", "
                << n_modes << " modes)";
              throw ParameterError("Absorbing boundary/Wave number range, Number of wave numbers",
                                   v.str(),
                                   "a mode set with condition number <= " +
                                     std::to_string(prm.max_condition_number) +
                                     " and max |V| <= " + std::to_string(prm.max_update_norm) +
                                     " after thinning (reduce Delta k or the number of modes)");
            }
          if (stride > 1)
            ++n_thinned;
          max_stride = std::max(max_stride, stride);
          max_cond   = std::max({max_cond, fg.cond, fh.cond});
          max_norm   = std::max({max_norm, fg.vmax, fh.vmax});
          WaveCloudInfo ci;
          ci.cond_g    = fg.cond;
          ci.cond_h    = fh.cond;
          ci.vmax_g    = fg.vmax;
          ci.vmax_h    = fh.vmax;
          ci.row_sum_g = fg.V.cwiseAbs().sum();
          ci.stride    = stride;
          info.push_back(ci);
          min_size   = std::min<unsigned int>(min_size, cloud.size());
          max_size   = std::max<unsigned int>(max_size, cloud.size());
          // Coefficients per point: an averaged entry spreads its V over its
          // block (points in id order for a rank-independent sum).
          std::map<types::global_dof_index, std::pair<unsigned int, std::array<double, 4>>> coeff;
          for (unsigned int j = 0; j < cloud.size(); ++j)
            for (const auto &q : members[j])
              {
                const unsigned int p  = cone[q.first].first;
                auto              &cf = coeff[ids[p]];
                cf.first              = p;
                cf.second[0] += q.second * fg.V[2 * j];
                cf.second[1] += q.second * fg.V[2 * j + 1];
                cf.second[2] += q.second * fh.V[2 * j];
                cf.second[3] += q.second * fh.V[2 * j + 1];
              }
          // Layer filter: + eps sum_{|x_j - x_i| <= dx} ((u_j - u_i)^n -
          // (u_j - u_i)^{n-1}), a lattice-Laplacian viscosity acting on the
          // time difference (a Laplacian of u^n itself would act as a
          // stiffness in the two-level recursion, not as damping); it damps
          // the mesh-scale waves (symbol up to 4 dim eps) and hardly the
          // fitted ones ((k dx)^2 eps).
          if (prm.layer_filter > 0.)
            {
              check_parameter(prm.n_time_levels == 2, "Absorbing boundary/Layer filter", prm.layer_filter,
                              "0 with one time level (the filter acts on u^n - u^{n-1})");
              const auto b0 = bin_of(xi);
              for (unsigned int nb = 0; nb < (dim == 1 ? 3u : 9u); ++nb)
                {
                  auto         b = b0;
                  unsigned int c = nb;
                  for (unsigned int d = 0; d < dim; ++d, c /= 3)
                    b[d] += long(c % 3) - 1;
                  const auto it = bins.find(b);
                  if (it == bins.end())
                    continue;
                  for (const unsigned int j : it->second)
                    if (j != i && xi.distance(points[j]) <= dx * (1. + 1e-6))
                      for (const auto &p : {std::make_pair(j, 1.), std::make_pair(i, -1.)})
                        {
                          auto &cf = coeff[ids[p.first]];
                          cf.first = p.first;
                          cf.second[0] += p.second * prm.layer_filter;
                          cf.second[1] -= p.second * prm.layer_filter;
                          cf.second[2] += p.second * prm.layer_filter;
                          cf.second[3] -= p.second * prm.layer_filter;
                        }
                }
            }
          // x_i first (as before), then by global id.
          std::vector<std::pair<unsigned int, std::array<double, 4>>> sorted_coeff{coeff[ids[i]]};
          for (const auto &cf : coeff)
            if (cf.first != ids[i])
              sorted_coeff.push_back(cf.second);
          for (const auto &cf : sorted_coeff)
            {
              cloud_index.push_back(cf.first);
              vg_now.push_back(cf.second[0]);
              vg_old.push_back(cf.second[1]);
              vh_now.push_back(cf.second[2]);
              vh_old.push_back(cf.second[3]);
            }
          cloud_start.push_back(cloud_index.size());
        }
      std::vector<std::array<double, 4>> own(cloud_index.size());
      for (unsigned int c = 0; c < own.size(); ++c)
        own[c] = {{vg_now[c], vg_old[c], vh_now[c], vh_old[c]}};
      store_updating_vectors(points, ids, normals, dx, own, node_modes, prm.share_updating_vectors, comm);
      all_cloud_points = cloud_index;
      std::sort(all_cloud_points.begin(), all_cloud_points.end());
      all_cloud_points.erase(std::unique(all_cloud_points.begin(), all_cloud_points.end()),
                             all_cloud_points.end());
      // compute_levels(): each entry's position among the cloud points.
      slot16.clear();
      slot32.clear();
      for (const unsigned int j : cloud_index)
        {
          const unsigned int p = std::lower_bound(all_cloud_points.begin(), all_cloud_points.end(), j) -
                                 all_cloud_points.begin();
          if (all_cloud_points.size() <= 65536)
            slot16.push_back(p);
          else
            slot32.push_back(p);
        }
      stats.n_absorbing = Utilities::MPI::sum<types::global_dof_index>(absorbing.size(), comm);
      stats.max_condition_number = Utilities::MPI::max(max_cond, comm);
      stats.max_update_norm      = Utilities::MPI::max(max_norm, comm);
      stats.min_cloud_size       = Utilities::MPI::min(min_size, comm);
      stats.max_cloud_size       = Utilities::MPI::max(max_size, comm);
      stats.n_thinned            = Utilities::MPI::sum(n_thinned, comm);
      stats.max_stride           = Utilities::MPI::max(max_stride, comm);
    }

    template <int dim>
    void
    EbfWaveAbc<dim>::store_updating_vectors(
      const std::vector<Point<dim>>                               &points,
      const std::vector<types::global_dof_index>                  &ids,
      const std::vector<Tensor<1, dim>>                           &normals,
      const double                                                 dx,
      const std::vector<std::array<double, 4>>                    &own,
      const std::vector<std::vector<std::array<double, dim + 3>>> &modes,
      const bool                                                   share,
      const MPI_Comm                                               comm)
    {
      const unsigned int n_nodes = absorbing.size();
      node_class.resize(n_nodes);
      class_start.assign(1, 0);
      coefficients.clear();
      stats.max_shared_difference = 0.;
      if (!share)
        {
          for (unsigned int a = 0; a < n_nodes; ++a)
            node_class[a] = a;
          class_start = cloud_start;
          coefficients = own;
          stats.n_classes = Utilities::MPI::sum<types::global_dof_index>(n_nodes, comm);
          return;
        }
      // Canonical form of each cloud: the entries sorted by their quantized
      // local-frame offsets, for the frame and its mirror image (2D), the
      // smaller key kept. The key also holds the node's modes (the sorted
      // quantized wave vectors in the same frame, frequencies and decay
      // rates: the discrete relation is anisotropic) and, as a guard (e.g.
      // other thinning weights), the own coefficients coarsely quantized.
      // The steps lie far above the round-off differences of symmetric
      // clouds (~1e-14 dx, 1e-16, ~eps cond), so that these are rarely split.
      const double offset_step = std::ldexp(dx, -20), mode_step = std::ldexp(1., -26),
                   coefficient_step = std::ldexp(1., -10);
      const auto   quantize    = [](const double x, const double step) {
        return static_cast<long long>(std::llround(x / step));
      };
      std::map<std::vector<long long>, unsigned int> local_class;
      // Per local class: the smallest global id of its members and that
      // member's coefficients in canonical order.
      std::vector<types::global_dof_index>             class_id;
      std::vector<std::vector<std::array<double, 4>>> class_coefficients;
      std::vector<std::vector<long long>>              class_key;
      std::vector<unsigned int>                        new_index(cloud_index.size());
      std::vector<unsigned int>                        order;
      for (unsigned int a = 0; a < n_nodes; ++a)
        {
          const unsigned int   begin = cloud_start[a], n = cloud_start[a + 1] - begin;
          const Tensor<2, dim> R     = local_frame(normals[a]);
          std::vector<std::array<long long, dim>> q(n);
          for (unsigned int c = 0; c < n; ++c)
            {
              const Tensor<1, dim> off = R * (points[cloud_index[begin + c]] - points[absorbing[a]]);
              for (unsigned int d = 0; d < dim; ++d)
                q[c][d] = quantize(off[d], offset_step);
            }
          std::vector<long long>    best_key;
          std::vector<unsigned int> best_order;
          for (unsigned int mirror = 0; mirror < (dim == 2 ? 2u : 1u); ++mirror)
            {
              if (mirror == 1)
                for (auto &p : q)
                  p[dim - 1] = -p[dim - 1];
              order.resize(n);
              for (unsigned int c = 0; c < n; ++c)
                order[c] = c;
              std::sort(order.begin(), order.end(), [&q](const unsigned int x, const unsigned int y) {
                return q[x] < q[y];
              });
              std::vector<long long> key{n};
              for (const unsigned int c : order)
                {
                  key.insert(key.end(), q[c].begin(), q[c].end());
                  for (const double v : own[begin + c])
                    key.push_back(quantize(v, coefficient_step));
                }
              std::vector<std::array<long long, dim + 3>> qm(modes[a].size());
              for (unsigned int c = 0; c < qm.size(); ++c)
                for (unsigned int d = 0; d < dim + 3; ++d)
                  qm[c][d] = quantize((mirror == 1 && d == dim - 1 ? -1. : 1.) * modes[a][c][d], mode_step);
              std::sort(qm.begin(), qm.end());
              for (const auto &m : qm)
                key.insert(key.end(), m.begin(), m.end());
              if (mirror == 0 || key < best_key)
                {
                  best_key.swap(key);
                  best_order = order;
                }
            }
          for (unsigned int c = 0; c < n; ++c)
            new_index[begin + c] = cloud_index[begin + best_order[c]];
          const auto [it, inserted] = local_class.emplace(best_key, class_id.size());
          const types::global_dof_index id = ids[absorbing[a]];
          if (inserted || id < class_id[it->second])
            {
              if (inserted)
                {
                  class_id.push_back(id);
                  class_coefficients.emplace_back();
                  class_key.push_back(best_key);
                }
              class_id[it->second] = id;
              auto &cf             = class_coefficients[it->second];
              cf.resize(n);
              for (unsigned int c = 0; c < n; ++c)
                cf[c] = own[begin + best_order[c]];
            }
          node_class[a] = it->second;
        }
      // Over all ranks, the member with the smallest global id provides the
      // coefficients of its class (flattened keys, ids and coefficients).
      std::map<std::vector<long long>, std::pair<types::global_dof_index, std::vector<std::array<double, 4>>>>
        global_class;
      if (Utilities::MPI::n_mpi_processes(comm) > 1)
        {
          std::vector<long long> flat_keys;
          std::vector<double>    flat_values;
          for (unsigned int k = 0; k < class_key.size(); ++k)
            {
              flat_keys.push_back(class_key[k].size());
              flat_keys.insert(flat_keys.end(), class_key[k].begin(), class_key[k].end());
              flat_keys.push_back(static_cast<long long>(class_id[k]));
              for (const auto &cf : class_coefficients[k])
                flat_values.insert(flat_values.end(), cf.begin(), cf.end());
            }
          const auto all_keys   = Utilities::MPI::all_gather(comm, flat_keys);
          const auto all_values = Utilities::MPI::all_gather(comm, flat_values);
          for (unsigned int r = 0; r < all_keys.size(); ++r)
            {
              std::size_t kp = 0, vp = 0;
              while (kp < all_keys[r].size())
                {
                  const std::size_t      len = all_keys[r][kp++];
                  std::vector<long long> key(all_keys[r].begin() + kp, all_keys[r].begin() + kp + len);
                  kp += len;
                  const auto id = static_cast<types::global_dof_index>(all_keys[r][kp++]);
                  const unsigned int n = key[0];
                  auto [it, inserted] = global_class.try_emplace(std::move(key));
                  if (inserted || id < it->second.first)
                    {
                      it->second.first = id;
                      it->second.second.resize(n);
                      for (unsigned int c = 0; c < n; ++c)
                        for (unsigned int v = 0; v < 4; ++v)
                          it->second.second[c][v] = all_values[r][vp + 4 * c + v];
                    }
                  vp += 4 * n;
                }
            }
          for (unsigned int k = 0; k < class_key.size(); ++k)
            class_coefficients[k] = global_class.at(class_key[k]).second;
        }
      stats.n_classes = global_class.empty() ? class_key.size() : global_class.size();
      for (unsigned int k = 0; k < class_key.size(); ++k)
        {
          class_start.push_back(class_start.back() + class_coefficients[k].size());
          coefficients.insert(coefficients.end(), class_coefficients[k].begin(), class_coefficients[k].end());
        }
      // What sharing changed against each node's own coefficients.
      double max_difference = 0.;
      for (unsigned int a = 0; a < n_nodes; ++a)
        {
          const unsigned int begin = cloud_start[a], n = cloud_start[a + 1] - begin;
          std::array<double, 4> scale{}, difference{};
          for (unsigned int c = 0; c < n; ++c)
            {
              // The own coefficient of the point now at canonical entry c.
              unsigned int e = begin;
              while (cloud_index[e] != new_index[begin + c])
                ++e;
              const auto &shared = coefficients[class_start[node_class[a]] + c];
              for (unsigned int v = 0; v < 4; ++v)
                {
                  scale[v]      = std::max(scale[v], std::abs(own[e][v]));
                  difference[v] = std::max(difference[v], std::abs(shared[v] - own[e][v]));
                }
            }
          for (unsigned int v = 0; v < 4; ++v)
            if (scale[v] > 0.)
              max_difference = std::max(max_difference, difference[v] / scale[v]);
        }
      stats.max_shared_difference = Utilities::MPI::max(max_difference, comm);
      cloud_index.swap(new_index);
    }

    namespace
    {
      // One absorbing node's sums (4.82): the four products of an entry,
      // coefficients times (u^n, u^{n-1}, v^n, v^{n-1}) of its point, go to
      // one 4-lane accumulator, acc = fma(cf[c], x, acc) lane by lane in the
      // node's entry order, and su = acc_0 + acc_1, sv = acc_2 + acc_3 at the
      // end: one vector FMA per entry instead of six scalar operations,
      // which bound the scalar sums (~3 cycles per entry). The scalar path
      // gives the same bits.
      struct Accumulator
      {
#if defined(__AVX2__) && defined(__FMA__)
        __m256d acc = _mm256_setzero_pd();
        void
        add(const std::array<double, 4> &cf, const std::array<double, 4> &x)
        {
          acc = _mm256_fmadd_pd(_mm256_loadu_pd(cf.data()), _mm256_loadu_pd(x.data()), acc);
        }
        void
        store(double &su, double &sv) const
        {
          alignas(32) double a[4];
          _mm256_store_pd(a, acc);
          su = a[0] + a[1];
          sv = a[2] + a[3];
        }
#else
        std::array<double, 4> acc = {{0., 0., 0., 0.}};
        void
        add(const std::array<double, 4> &cf, const std::array<double, 4> &x)
        {
          for (unsigned int k = 0; k < 4; ++k)
            acc[k] = std::fma(cf[k], x[k], acc[k]);
        }
        void
        store(double &su, double &sv) const
        {
          su = acc[0] + acc[1];
          sv = acc[2] + acc[3];
        }
#endif
      };
    } // namespace

    template <int dim>
    void
    EbfWaveAbc<dim>::compute_values(const double *u, const double *u_old, std::vector<double> &u_new) const
    {
      u_new.resize(absorbing.size());
      for (unsigned int a = 0; a < absorbing.size(); ++a)
        {
          const std::array<double, 4> *cf  = coefficients.data() + class_start[node_class[a]];
          const unsigned int          *idx = cloud_index.data() + cloud_start[a];
          const unsigned int           n   = cloud_start[a + 1] - cloud_start[a];
          double                       su  = 0.;
          for (unsigned int c = 0; c < n; ++c)
            su += cf[c][0] * u[idx[c]] + cf[c][1] * u_old[idx[c]];
          u_new[a] = su;
        }
    }

    template <int dim>
    void
    EbfWaveAbc<dim>::compute(const double        *u,
                             const double        *u_old,
                             const double        *v,
                             const double        *v_old,
                             std::vector<double> &u_new,
                             std::vector<double> &v_new) const
    {
      u_new.resize(absorbing.size());
      v_new.resize(absorbing.size());
      for (unsigned int a = 0; a < absorbing.size(); ++a)
        {
          // The class's coefficients in canonical order, the node's cloud
          // points in the same order.
          const std::array<double, 4> *cf  = coefficients.data() + class_start[node_class[a]];
          const unsigned int          *idx = cloud_index.data() + cloud_start[a];
          const unsigned int           n   = cloud_start[a + 1] - cloud_start[a];
          Accumulator                  acc;
          for (unsigned int c = 0; c < n; ++c)
            {
              const unsigned int j = idx[c];
              acc.add(cf[c], {{u[j], u_old[j], v[j], v_old[j]}});
            }
          acc.store(u_new[a], v_new[a]);
        }
    }

    namespace
    {
      // The sums of compute() on compact cloud data: x = levels[slot[c]]
      // holds (u^n, u^{n-1}, v^n, v^{n-1}) of the entry's point. Four nodes
      // per pass hide the FMA latency of their chains; a node's result does
      // not depend on the grouping (nor on the rank).
      template <typename Slot>
      void
      cloud_level_sums(const unsigned int           n_nodes,
                       const unsigned int          *cloud_start,
                       const Slot                  *slot,
                       const unsigned int          *node_class,
                       const unsigned int          *class_start,
                       const std::array<double, 4> *coefficients,
                       const std::array<double, 4> *levels,
                       double                      *u_new,
                       double                      *v_new)
      {
        constexpr unsigned int group = 4;
        const auto tail = [&](const unsigned int a, unsigned int c, Accumulator &acc) {
          const std::array<double, 4> *cf = coefficients + class_start[node_class[a]];
          const Slot                  *s  = slot + cloud_start[a];
          const unsigned int           n  = cloud_start[a + 1] - cloud_start[a];
          for (; c < n; ++c)
            acc.add(cf[c], levels[s[c]]);
          acc.store(u_new[a], v_new[a]);
        };
        unsigned int a = 0;
        for (; a + group <= n_nodes; a += group)
          {
            const std::array<double, 4> *cf[group];
            const Slot                  *s[group];
            unsigned int                 m = std::numeric_limits<unsigned int>::max();
            for (unsigned int g = 0; g < group; ++g)
              {
                cf[g] = coefficients + class_start[node_class[a + g]];
                s[g]  = slot + cloud_start[a + g];
                m     = std::min(m, cloud_start[a + g + 1] - cloud_start[a + g]);
              }
            Accumulator acc[group];
            for (unsigned int c = 0; c < m; ++c)
              for (unsigned int g = 0; g < group; ++g)
                acc[g].add(cf[g][c], levels[s[g][c]]);
            for (unsigned int g = 0; g < group; ++g)
              tail(a + g, m, acc[g]);
          }
        for (; a < n_nodes; ++a)
          {
            Accumulator acc;
            tail(a, 0, acc);
          }
      }
    } // namespace

    template <int dim>
    void
    EbfWaveAbc<dim>::initialize_levels(const double *u, const double *v, CloudLevels &levels) const
    {
      levels.resize(all_cloud_points.size());
      for (unsigned int p = 0; p < levels.size(); ++p)
        {
          const unsigned int j = all_cloud_points[p];
          levels[p]            = {{u[j], u[j], v[j], v[j]}};
        }
    }

    template <int dim>
    void
    EbfWaveAbc<dim>::compute_levels(const double        *u,
                                    const double        *v,
                                    CloudLevels         &levels,
                                    std::vector<double> &u_new,
                                    std::vector<double> &v_new) const
    {
      AssertDimension(levels.size(), all_cloud_points.size());
      u_new.resize(absorbing.size());
      v_new.resize(absorbing.size());
      // Gather level n; the previous one becomes level n-1.
      const unsigned int *points = all_cloud_points.data();
      for (unsigned int p = 0; p < levels.size(); ++p)
        {
          std::array<double, 4> &x = levels[p];
          const unsigned int     j = points[p];
          x[1]                     = x[0];
          x[3]                     = x[2];
          x[0]                     = u[j];
          x[2]                     = v[j];
        }
      if (slot32.empty())
        cloud_level_sums(absorbing.size(), cloud_start.data(), slot16.data(), node_class.data(),
                         class_start.data(), coefficients.data(), levels.data(), u_new.data(),
                         v_new.data());
      else
        cloud_level_sums(absorbing.size(), cloud_start.data(), slot32.data(), node_class.data(),
                         class_start.data(), coefficients.data(), levels.data(), u_new.data(),
                         v_new.data());
    }

    template <int dim>
    std::vector<unsigned int>
    EbfWaveAbc<dim>::cloud(const unsigned int a) const
    {
      return std::vector<unsigned int>(cloud_index.begin() + cloud_start[a],
                                       cloud_index.begin() + cloud_start[a + 1]);
    }


    template <int dim>
    PdUnboundedWave<dim>::PdUnboundedWave(const MPI_Comm comm)
      : disc(comm)
    {}

    template <int dim>
    void
    PdUnboundedWave<dim>::setup(const Domain<dim>                            &domain,
                                const LatticeParameters                      &lattice,
                                const ScalarWaveParameters                   &model,
                                const WaveTruncation                          boundary,
                                const WaveAbcParameters                      &prm_in,
                                const Function<dim>                          &initial,
                                const std::vector<std::array<Point<dim>, 2>> &notches)
    {
      check_parameter(domain.has_signed_distance(), "Geometry/Domain", "without signed distance",
                      "a box or a ball (the absorbing layer needs the distance to the boundary)");
      check_parameter(model.damping >= 0., "Model/Damping", model.damping, ">= 0");
      disc.setup(domain, lattice);
      // The operator and the time-step check of the PD wave solver.
      ScalarWaveParameters mp = model;
      {
        ScalarKernel kern;
        kern.dim      = dim;
        kern.omega    = model.omega;
        kern.exponent = model.exponent;
        kern.delta    = lattice.delta;
        if (mp.micro_constant <= 0.)
          mp.micro_constant = kern.micro_constant_for(model.wave_speed * model.wave_speed);
      }
      DiffusionModelParameters dp;
      dp.type              = "diffusion";
      dp.omega             = model.omega;
      dp.exponent          = model.exponent;
      dp.micro_diffusivity = mp.micro_constant;
      op                   = std::make_unique<DiffusionOperator<dim>>(disc, dp);
      const double dt_crit = 2. / std::sqrt(2. / op->critical_time_step());
      check_parameter(model.time_step > 0. && model.time_step <= dt_crit, "Time stepping/Time step",
                      model.time_step, "0 < dt <= " + std::to_string(dt_crit) +
                                         " (velocity-Verlet bound of the PD operator)");
      dt = model.time_step;
      d  = model.damping;
      t  = 0.;
      spectral_radius = 0.;
      u_prev.clear();
      v_half.clear();
      for (Vector *x : {&u, &v, &a, &Lu})
        disc.initialize_vector(*x);
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        u.local_element(i) = initial.value(disc.position[i]);
      const auto &nb = disc.neighborhood;
      bond_kernel_weight.resize(nb.bond_length.size());
      const ScalarKernel &kern = op->kernel();
      for (std::size_t e = 0; e < bond_kernel_weight.size(); ++e)
        bond_kernel_weight[e] = kern(std::min(nb.bond_length[e], kern.delta)) * nb.bond_weight[e];

      // Notches (Sect. 4.2.7): the bonds whose segment crosses one are broken.
      broken.clear();
      {
        const auto side = [](const Point<dim> &a, const Point<dim> &b, const Point<dim> &c) {
          return dim == 1 ? c[0] - a[0] : (b[0] - a[0]) * (c[dim - 1] - a[dim - 1]) - (b[dim - 1] - a[dim - 1]) * (c[0] - a[0]);
        };
        const auto crosses = [&](const Point<dim> &p, const Point<dim> &q, const std::array<Point<dim>, 2> &n) {
          if (dim == 1)
            return side(n[0], n[1], p) * side(n[0], n[1], q) < 0.;
          return side(n[0], n[1], p) * side(n[0], n[1], q) < 0. && side(p, q, n[0]) * side(p, q, n[1]) < 0.;
        };
        for (unsigned int i = 0; i < disc.n_owned() && !notches.empty(); ++i)
          for (std::uint64_t q = nb.row_start[i]; q < nb.row_start[i + 1]; ++q)
            {
              const unsigned int j = nb.col[q];
              for (const auto &n : notches)
                if (crosses(disc.position[i], disc.position[j], n))
                  {
                    broken.emplace_back(i, j, bond_kernel_weight[nb.table_start[i] + (q - nb.row_start[i])]);
                    break;
                  }
            }
      }

      u.update_ghost_values();
      v.update_ghost_values();
      apply_operator();
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        a.local_element(i) = Lu.local_element(i);
      cloud_levels.clear();
      operator_rows.clear();
      broken_operator_rows.clear();

      const bool sponge_only = boundary == WaveTruncation::sponge ||
                               (boundary == WaveTruncation::absorbing && prm_in.method == "sponge");
      const bool pml = boundary == WaveTruncation::pml ||
                       (boundary == WaveTruncation::absorbing && prm_in.method == "pml");
      absorbing = boundary != WaveTruncation::free && !sponge_only && !pml;
      // The sponge (not for the free truncation, which is the reference):
      // sigma(s) = sigma_max min(1, (s_in - s)/w)^p at depth s, s_in = the
      // overwritten layer (if any) plus w.
      damping.assign(disc.n_owned(), d);
      if (boundary != WaveTruncation::free && prm_in.sponge_damping > 0.)
        {
          const double s_in =
            prm_in.sponge_thickness +
            (absorbing ? (prm_in.layer_thickness > 0 ? prm_in.layer_thickness : lattice.delta) : 0.);
          const std::vector<double> sigma =
            sponge_profile<dim>(disc, domain, prm_in.sponge_damping, prm_in.sponge_thickness,
                                prm_in.sponge_exponent, s_in,
                                prm_in.cloud_radius > 0. ? prm_in.cloud_radius : lattice.delta);
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            damping[i] += sigma[i];
        }
      else
        check_parameter(!sponge_only, "Absorbing boundary/Sponge damping", prm_in.sponge_damping,
                        "> 0 with method sponge");

      // The PML (doc/design.md, session 8), shared with the elastic driver.
      pml_band.clear();
      if (pml)
        pml_band.reinit(disc, domain, bond_kernel_weight, prm_in.pml_damping, prm_in.pml_thickness,
                        prm_in.pml_exponent, dt, 1);
      if (prm_in.dispersion == "local")
        relation = std::make_unique<WaveDispersion<dim>>(
          WaveDispersion<dim>::local(model.wave_speed, d));
      else if (prm_in.dispersion == "nonlocal")
        relation = std::make_unique<WaveDispersion<dim>>(WaveDispersion<dim>::nonlocal(kern, d));
      else
        relation = std::make_unique<WaveDispersion<dim>>(
          WaveDispersion<dim>::discrete(kern, lattice.dx, lattice.partial_volume, d));
      if (!absorbing)
        return;

      WaveAbcParameters prm = prm_in;
      if (boundary == WaveTruncation::first_order)
        prm.method = "first order";
      const double      delta = lattice.delta;
      if (prm.cloud_radius <= 0.)
        prm.cloud_radius = delta;
      const double layer = prm.layer_thickness > 0 ? prm.layer_thickness : delta;
      std::vector<unsigned int>   nodes;
      std::vector<Tensor<1, dim>> normals;
      find_absorbing_layer(disc, domain, layer, prm.cloud_radius, nodes, normals);
      std::vector<types::global_dof_index> ids(disc.id.begin(), disc.id.end());
      // "interior": no absorbing point (owned or ghost, by the same distance
      // test as find_absorbing_layer) in any cloud.
      std::vector<bool> excluded;
      if (prm.cloud_points == "interior")
        for (const auto &p : disc.position)
          excluded.push_back(-domain.signed_distance(p) < layer - 1e-8 * lattice.dx);
      abc.reinit(disc.position, ids, nodes, normals, *relation, dt, lattice.dx, prm,
                 disc.get_mpi_communicator(), excluded);
      abc.initialize_levels(u.begin(), v.begin(), cloud_levels);
      // The overwritten rows need no operator sums: the others as ranges,
      // and their broken bonds.
      {
        std::vector<bool> overwritten(disc.n_owned(), false);
        for (const unsigned int i : abc.absorbing_points())
          overwritten[i] = true;
        for (unsigned int i = 0; i < disc.n_owned(); ++i)
          if (!overwritten[i])
            {
              if (operator_rows.empty() || operator_rows.back()[1] != i)
                operator_rows.push_back({{i, i + 1}});
              else
                ++operator_rows.back()[1];
            }
        for (const auto &b : broken)
          if (!overwritten[std::get<0>(b)])
            broken_operator_rows.push_back(b);
      }
      // The local guards do not imply stability of the coupled recursion
      // (doc/design.md): check the global one-step map where affordable.
      const std::size_t state = 2 * std::size_t(disc.n_owned()) + 2 * abc.cloud_points().size();
      if (prm.spectral_check_size > 0 && state <= prm.spectral_check_size &&
          Utilities::MPI::n_mpi_processes(disc.get_mpi_communicator()) == 1)
        {
          unsigned int         n_up = 0;
          std::complex<double> dominant;
          spectral_radius = one_step_spectral_radius(prm.spectral_check_size, &n_up, &dominant);
          if (spectral_radius > prm.max_spectral_radius)
            {
              // Locate the growing mode: the absorbing node (and cloud)
              // where the dominant eigenvector is largest.
              const WaveSpectralDiagnostics diag = spectral_diagnostics(prm.spectral_check_size);
              std::ostringstream v;
              v.precision(10);
              v << "one-step spectral radius " << spectral_radius << " (" << n_up
                << " eigenvalues of modulus > 1 + 1e-8, dominant angle " << std::arg(dominant)
                << " per step) of the near field with the absorbing boundary (" << state
                << " state entries; every cloud passed cond <= " << prm.max_condition_number
                << ", max |V| <= " << prm.max_update_norm << "); the dominant mode peaks at the "
                << describe_absorbing_node(diag.peak_absorbing) << " and has "
                << diag.layer_fraction << " of its norm in the absorbing layer";
              throw ParameterError("Absorbing boundary/Maximum spectral radius", v.str(),
                                   "<= " + std::to_string(prm.max_spectral_radius) +
                                     " (unstable: change the mode set, cone or layer)");
            }
        }
    }

    template <int dim>
    void
    PdUnboundedWave<dim>::advance()
    {
      using clock        = std::chrono::steady_clock;
      const auto   start = clock::now();
      static const std::vector<unsigned int> none;
      const bool                             use_abc = absorbing && !skip_abc;
      const std::vector<unsigned int>       &nodes   = use_abc ? abc.absorbing_points() : none;
      const double                           half    = 0.5 * dt;
      // (4.82) from the levels n and n-1 (ghosts of u, v are current).
      if (use_abc)
        abc.compute_levels(u.begin(), v.begin(), cloud_levels, u_abc, v_abc);
      const auto abc_end = clock::now();
      double    *uu = u.begin(), *vv = v.begin(), *aa = a.begin();
      u_prev.assign(uu, uu + disc.n_owned() + disc.n_ghost());
      v_half.resize(disc.n_owned());
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          uu[i] += dt * (vv[i] + half * aa[i]);
          vv[i] += half * aa[i];
          v_half[i] = vv[i];
        }

      for (unsigned int c = 0; c < nodes.size(); ++c)
        uu[nodes[c]] = u_abc[c];
      t += dt;
      u.update_ghost_values();
      apply_operator(!use_abc);
      pml_band.apply(true, {{u.begin()}}, {{Lu.begin()}});
      // Trapezoidal damping: v^{n+1/2} - v^{n-1/2} = dt L u^n - dt D (v^{n+1/2}
      // + v^{n-1/2}), so the half-step energy decays for any D >= 0.
      const double *lu = Lu.begin();
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          const double scale = 1. / (1. + dt * damping[i]);
          vv[i]              = scale * (vv[i] + half * lu[i]);
          aa[i] = lu[i] - 2. * damping[i] * vv[i];
        }
      const auto set_start = clock::now();
      for (unsigned int c = 0; c < nodes.size(); ++c)
        vv[nodes[c]] = v_abc[c];
      if (use_abc)
        v.update_ghost_values();
      const auto end = clock::now();
      abc_seconds += std::chrono::duration<double>(abc_end - start + end - set_start).count();
      step_seconds += std::chrono::duration<double>(end - start).count();
    }

    template <int dim>
    unsigned int
    PdUnboundedWave<dim>::assemble_one_step_map(const unsigned int max_size, std::vector<double> &map)
    {
      const MPI_Comm comm = disc.get_mpi_communicator();
      check_parameter(Utilities::MPI::n_mpi_processes(comm) == 1, "MPI ranks",
                      Utilities::MPI::n_mpi_processes(comm),
                      "1 (the spectral radius check assembles the dense one-step map)");
      const unsigned int               n = disc.n_owned();
      const std::vector<unsigned int> &c = abc.cloud_points();
      const unsigned int               n_abc = absorbing ? 2 * c.size() : 0;
      const unsigned int               n_bond = pml_band.bond_memory.size(), n_pml = pml_band.node_memory.size();
      const unsigned int               m     = 2 * n + n_abc + n_bond + n_pml;
      check_parameter(m <= max_size, "State size of the spectral radius check", m,
                      "<= " + std::to_string(max_size) + " (dense eigenvalue problem)");
      // Save the solver state.
      const Vector              u0 = u, v0 = v, a0 = a;
      const auto                levels0 = cloud_levels;
      const std::vector<double> up0 = u_prev, vh0 = v_half;
      const std::vector<double> bm0 = pml_band.bond_memory, nm0 = pml_band.node_memory;
      const double              t0 = t, abc0 = abc_seconds, step0 = step_seconds;
      const auto                set_state = [&](const std::vector<double> &x) {
        for (unsigned int i = 0; i < n; ++i)
          {
            u.local_element(i) = x[i];
            v.local_element(i) = x[n + i];
          }
        if (absorbing)
          for (unsigned int q = 0; q < c.size(); ++q)
            {
              cloud_levels[q][0] = x[2 * n + q];
              cloud_levels[q][2] = x[2 * n + c.size() + q];
            }
        std::copy(x.begin() + 2 * n + n_abc, x.begin() + 2 * n + n_abc + n_bond, pml_band.bond_memory.begin());
        std::copy(x.begin() + 2 * n + n_abc + n_bond, x.end(), pml_band.node_memory.begin());
        u.update_ghost_values();
        v.update_ghost_values();
        // The acceleration of a consistent state (only read at nodes whose
        // v is not overwritten by the absorbing update).
        apply_operator();
        pml_band.apply(false, {{u.begin()}}, {{Lu.begin()}});
        for (unsigned int i = 0; i < n; ++i)
          a.local_element(i) = Lu.local_element(i) - 2. * damping[i] * v.local_element(i);
      };
      map.assign(std::size_t(m) * m, 0.);
      std::vector<double> x(m);
      for (unsigned int col = 0; col < m; ++col)
        {
          std::fill(x.begin(), x.end(), 0.);
          x[col] = 1.;
          set_state(x);
          advance();
          double *column = map.data() + std::size_t(col) * m;
          for (unsigned int i = 0; i < n; ++i)
            {
              column[i]     = u.local_element(i);
              column[n + i] = v.local_element(i);
            }
          if (absorbing)
            for (unsigned int q = 0; q < c.size(); ++q)
              {
                column[2 * n + q]            = cloud_levels[q][0];
                column[2 * n + c.size() + q] = cloud_levels[q][2];
              }
          std::copy(pml_band.bond_memory.begin(), pml_band.bond_memory.end(), column + 2 * n + n_abc);
          std::copy(pml_band.node_memory.begin(), pml_band.node_memory.end(), column + 2 * n + n_abc + n_bond);
        }
      u     = u0;
      v     = v0;
      a     = a0;
      cloud_levels = levels0;
      u_prev = up0;
      v_half = vh0;
      pml_band.bond_memory = bm0;
      pml_band.node_memory = nm0;
      u.update_ghost_values();
      v.update_ghost_values();
      t            = t0;
      abc_seconds  = abc0;
      step_seconds = step0;
      return m;
    }

    template <int dim>
    double
    PdUnboundedWave<dim>::one_step_spectral_radius(const unsigned int    max_size,
                                                   unsigned int         *n_unstable,
                                                   std::complex<double> *dominant)
    {
      std::vector<double>      dense;
      const unsigned int       m = assemble_one_step_map(max_size, dense);
      LAPACKFullMatrix<double> map(m, m);
      for (unsigned int col = 0; col < m; ++col)
        for (unsigned int i = 0; i < m; ++i)
          map(i, col) = dense[std::size_t(col) * m + i];
      return Abc::spectral_radius(map, n_unstable, dominant);
    }

    template <int dim>
    WaveSpectralDiagnostics
    PdUnboundedWave<dim>::spectral_diagnostics(const unsigned int max_size)
    {
      WaveSpectralDiagnostics r;
      std::vector<double>     dense;
      const unsigned int      m = assemble_one_step_map(max_size, dense);
      const Eigen::Map<const Eigen::MatrixXd> A(dense.data(), m, m);
      {
        LAPACKFullMatrix<double> map(m, m);
        for (unsigned int col = 0; col < m; ++col)
          for (unsigned int i = 0; i < m; ++i)
            map(i, col) = A(i, col);
        map.compute_eigenvalues(false, false);
        for (unsigned int i = 0; i < m; ++i)
          {
            const double mod = std::abs(map.eigenvalue(i));
            if (mod > r.radius)
              {
                r.radius   = mod;
                r.dominant = map.eigenvalue(i);
              }
            r.n_unstable += mod > 1. + 1e-8 ? 1 : 0;
          }
      }
      // Inverse iteration with a shift next to the dominant eigenvalue.
      const std::complex<double> shift = r.dominant * (1. + 1e-9);
      const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(
        A.cast<std::complex<double>>() - shift * Eigen::MatrixXcd::Identity(m, m));
      Eigen::VectorXcd x = Eigen::VectorXcd::Ones(m);
      for (unsigned int it = 0; it < 4; ++it)
        {
          x = lu.solve(x);
          x /= x.norm();
        }
      const unsigned int               n = disc.n_owned();
      const std::vector<unsigned int> &c = abc.cloud_points();
      r.mode_u.resize(n);
      r.mode_v.resize(n);
      double peak = 0.;
      for (unsigned int i = 0; i < n; ++i)
        {
          r.eigenvector_u.push_back(x[i]);
          r.mode_u[i] = std::abs(x[i]);
          r.mode_v[i] = std::abs(x[n + i]);
          peak        = std::max({peak, r.mode_u[i], r.mode_v[i]});
        }
      for (unsigned int i = 0; i < n; ++i)
        {
          r.mode_u[i] /= peak;
          r.eigenvector_u[i] /= peak;
          r.mode_v[i] /= peak;
        }
      const auto &nodes = abc.absorbing_points();
      std::vector<unsigned int> sorted(nodes);
      std::sort(sorted.begin(), sorted.end());
      double      best  = -1.;
      for (unsigned int q = 0; q < nodes.size(); ++q)
        {
          const unsigned int i = nodes[q];
          r.layer_fraction += std::norm(x[i]) + std::norm(x[n + i]);
          r.absorbing_v_fraction += std::norm(x[n + i]);
          if (std::abs(x[i]) + std::abs(x[n + i]) > best)
            {
              best             = std::abs(x[i]) + std::abs(x[n + i]);
              r.peak_absorbing = q;
            }
        }
      if (absorbing)
        for (unsigned int q = 2 * n; q < m; ++q)
          r.layer_fraction += std::norm(x[q]) * (std::binary_search(sorted.begin(), sorted.end(), c[(q - 2 * n) % c.size()]) ? 1. : 0.);
      return r;
    }

    template <int dim>
    std::string
    PdUnboundedWave<dim>::describe_absorbing_node(const unsigned int q) const
    {
      std::ostringstream s;
      const unsigned int i  = abc.absorbing_points()[q];
      const auto        &ci = abc.cloud_info(q);
      s << "absorbing node " << disc.id[i] << " at (" << disc.position[i] << "): cloud of "
        << abc.cloud(q).size() << " points (stride " << ci.stride << "), cond(M_G) " << ci.cond_g
        << ", cond(M_H) " << ci.cond_h << ", max |V_G| " << ci.vmax_g << ", max |V_H| " << ci.vmax_h
        << ", sum |V_G| " << ci.row_sum_g;
      return s.str();
    }

    template <int dim>
    void
    PdUnboundedWave<dim>::apply_operator(const bool all_rows)
    {
      const bool    skip = !all_rows && !operator_rows.empty();
      if (skip)
        op->apply(u, Lu, operator_rows);
      else
        op->apply(u, Lu);
      const double *uu = u.begin();
      double       *lu = Lu.begin();
      for (const auto &[i, j, w] : skip ? broken_operator_rows : broken)
        lu[i] -= w * (uu[j] - uu[i]);
    }

    template <int dim>
    std::uint64_t
    PdUnboundedWave<dim>::n_broken_bonds() const
    {
      return Utilities::MPI::sum<std::uint64_t>(broken.size(), disc.get_mpi_communicator());
    }

    template <int dim>
    double
    PdUnboundedWave<dim>::energy(const std::function<bool(const Point<dim> &)> &inside) const
    {
      const auto   &nb = disc.neighborhood;
      const double *uu = u.begin();
      double        e  = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          if (!inside(disc.position[i]))
            continue;
          const double *w   = bond_kernel_weight.data() + nb.table_start[i];
          double        row = 0.;
          for (std::uint64_t q = nb.row_start[i]; q < nb.row_start[i + 1]; ++q)
            {
              const double du = uu[nb.col[q]] - uu[i];
              row += w[q - nb.row_start[i]] * du * du;
            }
          const double vi = v.local_element(i);
          e += (0.5 * vi * vi + 0.25 * row) * disc.volume[i];
        }
      for (const auto &[i, j, w] : broken)
        if (inside(disc.position[i]))
          e -= 0.25 * w * (uu[j] - uu[i]) * (uu[j] - uu[i]) * disc.volume[i];
      return Utilities::MPI::sum(e, disc.get_mpi_communicator());
    }

    template <int dim>
    double
    PdUnboundedWave<dim>::half_step_energy() const
    {
      AssertThrow(!u_prev.empty(), ExcMessage("half_step_energy() needs one advance()"));
      const auto   &nb = disc.neighborhood;
      const double *uu = u.begin();
      double        e  = 0.;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          const double *w   = bond_kernel_weight.data() + nb.table_start[i];
          double        row = 0.;
          for (std::uint64_t q = nb.row_start[i]; q < nb.row_start[i + 1]; ++q)
            {
              const unsigned int j = nb.col[q];
              row += w[q - nb.row_start[i]] * (uu[j] - uu[i]) * (u_prev[j] - u_prev[i]);
            }
          e += (0.5 * v_half[i] * v_half[i] + 0.25 * row) * disc.volume[i];
        }
      for (const auto &[i, j, w] : broken)
        e -= 0.25 * w * (uu[j] - uu[i]) * (u_prev[j] - u_prev[i]) * disc.volume[i];
      return Utilities::MPI::sum(e, disc.get_mpi_communicator());
    }

    template <int dim>
    double
    PdUnboundedWave<dim>::value_at(const Point<dim> &p) const
    {
      double       best = std::numeric_limits<double>::max(), value = 0.;
      unsigned int best_id = 0;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          const double dd = p.distance(disc.position[i]);
          if (dd < best - 1e-12)
            {
              best    = dd;
              value   = u.local_element(i);
              best_id = disc.id[i];
            }
        }
      const MPI_Comm comm   = disc.get_mpi_communicator();
      const double   global = Utilities::MPI::min(best, comm);
      // The owner of the nearest node (lowest id on ties) reports its value.
      const unsigned int owner_id = Utilities::MPI::min(
        std::abs(best - global) <= 1e-12 ? best_id : std::numeric_limits<unsigned int>::max(), comm);
      return Utilities::MPI::sum(
        (std::abs(best - global) <= 1e-12 && best_id == owner_id) ? value : 0., comm);
    }

    template <int dim>
    std::vector<std::pair<Point<dim>, double>>
    PdUnboundedWave<dim>::gather(const std::function<bool(const Point<dim> &)> &inside) const
    {
      std::vector<double> local;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        if (inside(disc.position[i]))
          {
            for (unsigned int dd = 0; dd < dim; ++dd)
              local.push_back(disc.position[i][dd]);
            local.push_back(u.local_element(i));
          }
      const auto all = Utilities::MPI::all_gather(disc.get_mpi_communicator(), local);
      std::vector<std::pair<Point<dim>, double>> out;
      for (const auto &chunk : all)
        for (std::size_t q = 0; q + dim < chunk.size(); q += dim + 1)
          {
            Point<dim> p;
            for (unsigned int dd = 0; dd < dim; ++dd)
              p[dd] = chunk[q + dd];
            out.emplace_back(p, chunk[q + dim]);
          }
      return out;
    }

    template class WaveDispersion<1>;
    template class WaveDispersion<2>;
    template class EbfWaveAbc<1>;
    template class EbfWaveAbc<2>;
    template class PdUnboundedWave<1>;
    template class PdUnboundedWave<2>;
  } // namespace Abc
} // namespace PeriDEAL
