#ifndef perideal_abc_ebf_wave_abc_h
#define perideal_abc_ebf_wave_abc_h

#include <deal.II/base/bounding_box.h>
#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>
#include <deal.II/base/types.h>

#include <perideal/abc/absorbing_layer.h>
#include <perideal/base/kernel.h>
#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/models/diffusion.h>
#include <perideal/models/scalar_wave.h>

#include <array>
#include <complex>
#include <cstdint>
#include <tuple>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  namespace Abc
  {
    /**
     * Parameters of the EBF absorbing boundary for (viscous) scalar waves
     * (dissertation Sect. 4.2.3): wave numbers k in [-Delta k, Delta k] and
     * directions phi in [-Delta phi, Delta phi] about the outward normal
     * (4.56), the conic extrapolation region (4.86) and the stability guards.
     */
    struct WaveAbcParameters
    {
      /** Subdivisions n_k of [-Delta k, Delta k] (n_k + 1 wave numbers, (4.98)). */
      unsigned int n_wave_numbers = 10;
      /** Delta k (4.56); must satisfy 0 < Delta k <= pi/dx (4.83). */
      double wave_number_range = 1.;
      /** Subdivisions n_phi of [-Delta phi, Delta phi] (2D; n_phi + 1 directions). */
      unsigned int n_directions = 10;
      /** Delta phi of the mode directions (4.56). */
      double direction_range = M_PI / 4.;
      /** Delta phi of the conic extrapolation region (4.86). */
      double cone_angle = M_PI / 4.;
      /** Cloud radius (0: the horizon delta for PD, 2 dx for FEM). */
      double cloud_radius = 0.;
      /**
       * Cloud size n (session 19): 0 = every cone point within the cloud
       * radius (the source); n > 0 = x_i and its n nearest cone points
       * (points at the same distance as the n-th are kept too), i.e. a
       * per-node radius grown until the cloud holds n points, so that the
       * cloud composition does not depend on where a fixed radius falls on
       * a curved mesh. The cloud radius is then only the search radius (FEM
       * default 2 n dx).
       */
      unsigned int cloud_size = 0;
      /** PD absorbing layer thickness delta_L (0: the horizon). */
      double layer_thickness = 0.;
      /** "local" (4.39), "nonlocal" (continuum PD, (4.47)/(4.51)/(4.90)) or "discrete" (4.85)/(4.95). */
      std::string dispersion = "discrete";
      /** Guard: largest admissible moment-matrix condition number. */
      double max_condition_number = 1e12;
      /** Guard: largest admissible max_j |V_j| (Sect. 4.2.3: 2). */
      double max_update_norm = 2.;
      /**
       * Relative singular-value cutoff of the pseudo-inverse (0: Eigen's
       * default rank threshold max(rows, cols) * epsilon); LAPACK's rcond.
       * The condition number guard is evaluated over the retained singular
       * values (E12c: 1e-12).
       */
      double pseudo_inverse_tolerance = 0.;
      /**
       * How the pseudo-inverse treats the small singular values: "truncate"
       * (LAPACK's rcond: 1/sigma for sigma > tol sigma_max, else 0) or
       * "tikhonov" (sigma/(sigma^2 + lambda^2) with lambda = tol sigma_max
       * for every sigma above the default rank threshold): a continuous
       * family between two truncation ranks.
       */
      std::string pseudo_inverse_regularization = "truncate";
      /**
       * PD, serial runs: if the state size 2 n_nodes + 2 n_cloud_points is at
       * most this, setup computes the spectral radius of the one-step map
       * (PdUnboundedWave::one_step_spectral_radius) and throws
       * ParameterError if it exceeds max_spectral_radius (0: no check).
       */
      unsigned int spectral_check_size = 0;
      /** Time levels of the cloud data in (4.79): 2 (n and n-1) or 1 (n only). */
      unsigned int n_time_levels = 2;
      /** Largest admissible one-step spectral radius of the checked map. */
      double max_spectral_radius = 1. + 1e-8;
      /**
       * Store one set of updating vectors per congruence class of clouds
       * (EbfWaveAbc::reinit) instead of one per absorbing node: fewer
       * coefficient bytes streamed per step, results equal to round-off.
       */
      bool share_updating_vectors = true;
      /**
       * PD: "all" (the source: every point of the cone, absorbing ones
       * included) or "interior" (no absorbing point in any cloud, so that no
       * absorbing value is extrapolated from extrapolated values).
       */
      std::string cloud_points = "all";
      /**
       * Auxiliary-grid thinning (Fig. 4.23): "nearest" (the source: the node
       * nearest to each auxiliary node) or "average" (the mean of the nodes
       * in each auxiliary cell, which does not alias the shortest lattice
       * waves onto smooth ones).
       */
      std::string thinning = "nearest";
      /**
       * Mesh-scale modes added to the mode set: "none" (the source),
       * "corner" (standing waves at the Brillouin-zone corner
       * K = (pi/dx, ..., pi/dx), the top of the PD lattice spectrum) or "zone"
       * (corner and face centres pi/dx e_d), with the frequency of the
       * dispersion relation, so that the extrapolation follows these
       * non-propagating lattice waves instead of amplifying them.
       */
      std::string lattice_modes = "none";
      /** Extra decay rate of the lattice modes (>= 0: the extrapolation damps them). */
      double lattice_mode_damping = 0.;
      /**
       * 1D with a lattice (discrete) relation Omega^2(k) = sum_j a_j (1 -
       * cos(k j dx)): evanescent lattice modes added to the mode set. For
       * every mode k_m > 0 the other roots z = exp(i k dx) of Omega^2(z) =
       * Omega^2(k_m) (complex k at the same frequency, 2J roots for J
       * lattice neighbours, two of them k_m and -k_m) are added with the
       * mode's frequency and their complex conjugates: "none" (the source),
       * "outgoing" (|z| < 1: decaying outward, the evanescent part of the
       * exact discrete transparent condition; doc/design.md, session 19).
       */
      std::string evanescent_modes = "none";
      /**
       * eps of the layer filter: eps sum_j ((u_j - u_i)^n - (u_j - u_i)^{n-1})
       * over the nodes within dx of x_i is added to u_i^{n+1} (and likewise
       * to v), a lattice-Laplacian viscosity folded into V_G, V_H (0: the
       * source; needs two time levels).
       */
      double layer_filter = 0.;
      /**
       * "value" (the source: V_G = Psi(0, dt) M_G^+, V_H likewise) or
       * "increment": the fit extrapolates the change over one step,
       * V_G = e_i + (Psi(0, dt) - Psi(0, 0)) M_G^+ (e_i: the level-n entry
       * of x_i; V_H likewise). Identical when M^+ reproduces Psi(0, 0)
       * (x_i is in its cloud and no singular value is cut); with a
       * truncated pseudo-inverse only the increment is filtered, so that
       * V -> e_i as dt -> 0 (doc/design.md, session 11).
       */
      std::string fit_form = "value";
      /**
       * 2D: radius rho of the wave fronts at the boundary for the mode set
       * (0: plane modes, the source). With rho > 0 every mode is evaluated in
       * the polar coordinates about x_i - rho n, s = (r - rho, rho theta),
       * with the cylindrical amplitude sqrt(rho / r): the normal modes
       * become outgoing cylindrical waves (WKB), which a plane-wave fit over
       * a cloud of a curved boundary cannot represent when k rho is small
       * (FEM disks, doc/design.md, session 12). Typically the radius of a
       * disk near field centred at the source.
       */
      double curvature_radius = 0.;
      /**
       * 2D: curvature radius of the harmonic modes with |k| <= wake_wave_number
       * (0, the default: curvature_radius for every mode). A smaller radius
       * for the long waves gives them the larger decay (u_t + chi u_s) / u
       * = -(d + 1 / (2 rho)) of the slowly varying 2D wake behind the front,
       * while the shorter waves of the front keep curvature_radius.
       */
      double wake_curvature_radius = 0.;
      /** Largest |k| of the modes with the wake curvature radius. */
      double wake_wave_number = 0.;
      /**
       * 2D, with wake_curvature_radius > 0: exponent p of a per-node wake
       * radius rho_w cos(theta_i)^p, theta_i the angle between the node's
       * outward normal and x_i - c (c: the centroid of the absorbing nodes,
       * e.g. the centre of a square near field). A wake from the centre meets
       * the edge nodes near a corner obliquely (theta up to 45 degrees); its
       * one-way decay (u_t + chi u_n) / u grows there, i.e. it needs a smaller
       * radius than at the edge centres. 0 (the default): one radius.
       */
      double wake_angle_exponent = 0.;
      /**
       * "ebf" (the EBF extrapolation (4.82)) or "first order": the
       * conventional first-order ABC (4.75) u^{n+1} = u^n - dt (chi du/dn + d u^n),
       * with du/dn from a least-squares linear fit over x_i and the cone
       * points within min(d_inf, 2 dx) (same for v); chi is the long-wave
       * speed of the dispersion relation; "sponge" or "pml" (PD, below).
       * PdUnboundedElastic takes ebf, first order, sponge or pml.
       */
      std::string method = "ebf";
      /**
       * PD: largest extra damping rate sigma_max of the sponge (0: none).
       * The nodes at depth s (distance to the truncation boundary) below
       * s_in = (overwritten layer ? delta_L : 0) + w get the extra damping
       * sigma(s) = sigma_max min(1, (s_in - s)/w)^p in
       * u'' = L u - 2 (d + sigma) u' (w: "Sponge thickness", p: "Sponge
       * exponent"). With method "sponge" nothing is overwritten and the
       * semi-discrete and the discrete (velocity Verlet) energies are
       * non-increasing (doc/design.md, session 7); with "ebf" or "first
       * order" the sponge lies inside the overwritten layer.
       */
      double sponge_damping = 0.;
      /** Sponge width w (> 0 when sponge_damping > 0). */
      double sponge_thickness = 0.;
      /** Exponent p of the sponge profile. */
      double sponge_exponent = 2.;
      /**
       * PD (scalar and elastic waves), method "pml": largest damping rate
       * sigma_max of the perfectly matched layer (PmlBand; doc/design.md,
       * sessions 8-9): complex stretching of the
       * normal coordinate, x_n -> x_n + (i/omega) Sigma(x_n), applied to the
       * nonlocal operator bond by bond. The normal part of a bond (weight
       * g = (n . xi/|xi|)^2, n: outward normal) has its difference u_j - u_i
       * divided by
       * s_ij = 1 + i sigma_ij/omega (sigma_ij: the mean of sigma along the
       * bond, (Sigma_j - Sigma_i)/(rho_j - rho_i)) and the sum over the bonds
       * by s_i = 1 + i sigma_i/omega; in time both divisions are exponential
       * memory variables (one per bond of the nodes within w + delta of the
       * boundary, one per node). sigma(rho) = sigma_max (rho/w)^p at the
       * distance rho = w - depth into the PML. Nothing is overwritten.
       */
      double pml_damping = 0.;
      /** PML width w (the outermost w of the near field; >= 2 dx). */
      double pml_thickness = 0.;
      /** Exponent p of the PML profile (>= 1). */
      double pml_exponent = 2.;

      static void
      declare_parameters(ParameterHandler &prm);
      /** The caller has entered "Absorbing boundary". */
      void
      parse_parameters(ParameterHandler &prm);
    };

    /**
     * Dispersion relation of the harmonic far-field modes
     * psi = exp(-d t) exp(i k n.x - i omega~(k n) t) (4.53), (4.57), written
     * through the symbol Omega^2(k) of the (discrete or continuum) spatial
     * operator, -L exp(i k.x) = Omega^2(k) exp(i k.x):
     * omega~ = sign(k) sqrt(Omega^2 - d^2) (complex root when d^2 > Omega^2,
     * then the slowly decaying overdamped branch), so that every mode with
     * k < 0 is the complex conjugate of one with k > 0 and all travel outward.
     */
    template <int dim>
    class WaveDispersion
    {
    public:
      /** Omega^2 = chi^2 |k|^2 (4.39). */
      static WaveDispersion
      local(const double wave_speed, const double damping);
      /**
       * Continuum PD relation Omega^2(k) = int_H k(|xi|) (1 - cos(k.xi)) dxi
       * (4.43), by radial Gauss quadrature of the closed-form angular
       * integral (1D: 2 (1 - cos kr), 2D: 2 pi (1 - J_0(kr))); its Taylor
       * series are (4.47), (4.51) and its 1D p = 0 form is (4.90).
       */
      static WaveDispersion
      nonlocal(const ScalarKernel &kernel, const double damping);
      /**
       * Discrete relation (4.85)/(4.95) of the standard meshfree scheme:
       * Omega^2(k) = sum_{j in F_0} k(|x_j|) (1 - cos(k.x_j)) beta(|x_j|) dx^dim
       * over the lattice family of the origin with the near field's own
       * volume factor (Discretization::volume_factor).
       */
      static WaveDispersion
      discrete(const ScalarKernel &kernel, const double dx, const bool partial_volume,
               const double damping);
      /**
       * The same with an explicit stencil (offsets xi_j and weights w_j,
       * Omega^2 = sum_j w_j (1 - cos(k.xi_j))), e.g. a FEM row. With a mass
       * stencil (diagonal m_0, offsets eta_j, weights m_j) the symbol is
       * divided by the mass symbol m_0 + sum_j m_j cos(k.eta_j): the
       * semi-discrete relation of a consistent-mass FEM row.
       */
      static WaveDispersion
      stencil(const std::vector<Tensor<1, dim>> &offsets, const std::vector<double> &weights,
              const double damping, const std::string &name,
              const double mass_diagonal = 1., const std::vector<Tensor<1, dim>> &mass_offsets = {},
              const std::vector<double> &mass_weights = {});

      /** Omega^2 for the wave vector @p k (global frame). */
      double
      symbol(const Tensor<1, dim> &k) const
      {
        return omega2(k);
      }
      /** omega~ for wave number @p k (signed) along unit direction @p n. */
      std::complex<double>
      frequency(const double k, const Tensor<1, dim> &n) const;
      /** Damping d. */
      double damping = 0.;
      /** "local", "nonlocal", "discrete" or a stencil name. */
      std::string name;

    private:
      std::function<double(const Tensor<1, dim> &)> omega2;
    };

    /** Summary of the clouds after setup (global over all ranks). */
    struct WaveCloudStatistics
    {
      types::global_dof_index n_absorbing = 0;
      unsigned int            min_cloud_size = 0, max_cloud_size = 0;
      /** Number of modes n_b. */
      unsigned int n_modes = 0;
      /** Largest condition numbers of M_G and M_H (over retained singular values). */
      double max_condition_number = 0.;
      /** Largest max-norm of V_G and V_H. */
      double max_update_norm = 0.;
      /** Clouds that were thinned (auxiliary-grid stride > 1) and the largest stride. */
      unsigned int n_thinned = 0, max_stride = 1;
      /**
       * Distinct sets of updating vectors stored, over all ranks (the
       * congruence classes; n_absorbing without sharing).
       */
      types::global_dof_index n_classes = 0;
      /**
       * Largest max_j |V_shared,j - V_own,j| / max_j |V_own,j| over the
       * absorbing nodes and the four coefficient vectors (V_G, V_H of both
       * levels): what sharing changed against each node's own fit.
       */
      double max_shared_difference = 0.;
    };

    /** Guard numbers of one cloud (after thinning). */
    struct WaveCloudInfo
    {
      /** Condition numbers of M_G, M_H and max_j |V_G,j|, max_j |V_H,j|. */
      double cond_g = 0., cond_h = 0., vmax_g = 0., vmax_h = 0.;
      /** sum_j |V_G,j| over both time levels (the row sum of the u update). */
      double row_sum_g = 0.;
      /** Auxiliary-grid stride of the retained cloud (1: not thinned). */
      unsigned int stride = 1;
    };

    /**
     * Result of PdUnboundedWave::one_step_spectral_radius() with the
     * dominant eigenvector located on the nodes.
     */
    struct WaveSpectralDiagnostics
    {
      double               radius = 0.;
      unsigned int         n_unstable = 0;
      std::complex<double> dominant;
      /** |u| and |v| of the dominant eigenvector per owned node (max of both = 1). */
      std::vector<double> mode_u, mode_v;
      /** The u part of the dominant eigenvector per owned node (same scaling): its phase pattern. */
      std::vector<std::complex<double>> eigenvector_u;
      /** Share of the squared dominant eigenvector on the absorbing nodes (u, v, old levels). */
      double layer_fraction = 0.;
      /** Share of the squared dominant eigenvector in the v entries of the absorbing nodes. */
      double absorbing_v_fraction = 0.;
      /** Index (into absorbing_points()) of the absorbing node with the largest |u| + |v|. */
      unsigned int peak_absorbing = 0;
    };

    /**
     * The EBF absorbing boundary for viscous scalar waves (Sect. 4.2.3):
     * for every owned absorbing node x_i a local frame with x along the
     * outward normal, the cloud restricted to the conic extrapolation region
     * (4.86) behind x_i, the complex outgoing modes (4.57) with the given
     * dispersion relation, the moment matrices M_G, M_H of two time levels
     * (4.79), their Moore-Penrose inverses (Eigen SVD) and the updating vectors V_G = Psi(0, dt) M_G^+,
     * V_H = Psi'(0, dt) M_H^+ (4.82). If a cloud violates the guards
     * (condition number, max |V|) it is thinned by the nearest nodes to an
     * auxiliary grid of growing stride in the local frame
     * (Fig. 4.23) until the guards hold; otherwise ParameterError.
     *
     * Shared updating vectors (WaveAbcParameters::share_updating_vectors):
     * nodes whose final clouds are congruent in their local frames (the same
     * offsets R (x_j - x_i), possibly after the reflection y bar -> -y bar,
     * to 2^-20 dx), with the same modes (local wave vectors, frequencies and
     * decay rates to 2^-26) and their own coefficients the same to 2^-10,
     * have the same moment matrices up to round-off, so only one set of coefficients
     * per such class is stored, with the cloud of each node listed in the
     * class's canonical order (offsets sorted). The stored set is the own
     * fit of the class member with the smallest global id over all ranks,
     * so it does not depend on the partition.
     */
    template <int dim>
    class EbfWaveAbc
    {
    public:
      /**
       * Precompute everything. @p points / @p ids: all points available on
       * this rank (owned and ghost, local numbering) with global ids;
       * @p absorbing: local indices of the owned absorbing points,
       * @p outward_normals their normals; @p dx the near-field spacing (for
       * (4.83) and the auxiliary grid); @p excluded (optional, per point):
       * points that may not enter any cloud.
       */
      void
      reinit(const std::vector<Point<dim>>              &points,
             const std::vector<types::global_dof_index> &ids,
             const std::vector<unsigned int>            &absorbing,
             const std::vector<Tensor<1, dim>>          &outward_normals,
             const WaveDispersion<dim>                  &dispersion,
             const double                                time_step,
             const double                                dx,
             const WaveAbcParameters                    &parameters,
             const MPI_Comm                              comm,
             const std::vector<bool>                    &excluded = {});

      /**
       * u_new[a] = V_G . (u^n_j, u^{n-1}_j)_j, v_new[a] = V_H . (v^n_j, v^{n-1}_j)_j
       * for every absorbing node a (arrays in local numbering, ghosts valid).
       */
      void
      compute(const double        *u,
              const double        *u_old,
              const double        *v,
              const double        *v_old,
              std::vector<double> &u_new,
              std::vector<double> &v_new) const;

      /** Only u_new[a] = V_G . (u^n_j, u^{n-1}_j)_j (callers that derive v otherwise). */
      void
      compute_values(const double *u, const double *u_old, std::vector<double> &u_new) const;

      /**
       * Cloud data of compute_levels(): per entry p of cloud_points()
       * (u^n, u^{n-1}, v^n, v^{n-1}) at that point.
       */
      using CloudLevels = std::vector<std::array<double, 4>>;

      /**
       * The start with level n-1 equal to level n: @p levels [p] =
       * (u, u, v, v) at cloud point p (@p u, @p v in local numbering, ghosts
       * valid).
       */
      void
      initialize_levels(const double *u, const double *v, CloudLevels &levels) const;

      /**
       * compute() on compact cloud data: on entry @p levels holds level
       * n-1 in its entries 0 and 2 (the previous call's level n, or
       * initialize_levels()); level n is gathered from @p u, @p v into them
       * (the old values moving to entries 1 and 3) and u_new, v_new are
       * compute()'s sums, the same products in the same order. Per cloud
       * entry it reads 32 contiguous bytes and a 16-bit slot (at most 65,536
       * cloud points, else 32-bit) instead of four full-size arrays at a
       * 32-bit index, and no level n-1 copy is written back.
       */
      void
      compute_levels(const double        *u,
                     const double        *v,
                     CloudLevels         &levels,
                     std::vector<double> &u_new,
                     std::vector<double> &v_new) const;

      const std::vector<unsigned int> &
      absorbing_points() const
      {
        return absorbing;
      }
      /** Sorted unique local indices of all cloud points (what compute() reads). */
      const std::vector<unsigned int> &
      cloud_points() const
      {
        return all_cloud_points;
      }
      /** Cloud (local indices) of absorbing point a. */
      std::vector<unsigned int>
      cloud(const unsigned int a) const;
      const WaveCloudStatistics &
      statistics() const
      {
        return stats;
      }
      /** Guard numbers of the cloud of absorbing point a. */
      const WaveCloudInfo &
      cloud_info(const unsigned int a) const
      {
        return info[a];
      }
      /** Rotation R with R n = e_1 (the local frame of Fig. 4.20). */
      static Tensor<2, dim>
      local_frame(const Tensor<1, dim> &outward_normal);

    private:
      /**
       * Group the clouds into classes and store one coefficient set per
       * class (one per node if @p share is false); @p own: each node's
       * coefficients (V_G, V_H of levels n and n-1) per entry of cloud_index;
       * @p modes: each node's modes (local wave vector, Re and Im of the
       * frequency, decay rate).
       */
      void
      store_updating_vectors(const std::vector<Point<dim>>                               &points,
                             const std::vector<types::global_dof_index>                  &ids,
                             const std::vector<Tensor<1, dim>>                           &normals,
                             const double                                                 dx,
                             const std::vector<std::array<double, 4>>                    &own,
                             const std::vector<std::vector<std::array<double, dim + 3>>> &modes,
                             const bool                                                   share,
                             const MPI_Comm                                               comm);

      std::vector<unsigned int> absorbing, cloud_start, cloud_index, all_cloud_points;
      /**
       * Per entry of cloud_index: its position in all_cloud_points
       * (compute_levels()), 16 bits if there are at most 65,536 cloud points
       * (slot16), else 32 bits (slot32); the other one is empty.
       */
      std::vector<std::uint16_t> slot16;
      std::vector<std::uint32_t> slot32;
      /** Class of each absorbing node and the start of each class in coefficients. */
      std::vector<unsigned int> node_class, class_start;
      /** Per class entry: V_G and V_H for levels n and n-1. */
      std::vector<std::array<double, 4>> coefficients;
      std::vector<WaveCloudInfo> info;
      WaveCloudStatistics stats;
    };

    /** How the truncation boundary of a wave near field is treated. */
    enum class WaveTruncation
    {
      /** The EBF absorbing boundary. */
      absorbing,
      /** Nothing: a free PD surface (reflecting). Used for the extended reference. */
      free,
      /**
       * The conventional first-order ABC (4.75), u_t + chi du/dn + d u = 0,
       * on the same absorbing layer: forward Euler in time, du/dn by a
       * least-squares linear fit over the cone behind the node (the
       * baseline of Sect. 4.2.5).
       */
      first_order,
      /**
       * Only the damping sponge of WaveAbcParameters (method "sponge"):
       * nothing is overwritten, the free PD near field is damped near its
       * boundary; energy-stable by construction.
       */
      sponge,
      /** Only the split-field PML of WaveAbcParameters (method "pml"). */
      pml
    };

    /**
     * PD scalar wave near field (2.40) on a truncated domain (box or ball):
     * damped velocity Verlet (3.9)/(4.62) through the DiffusionOperator with
     * kernel c_s omega / |xi|^p, and the EBF absorbing boundary on the nodes
     * within delta_L of the truncation boundary (Sect. 4.2.3, 4.2.4, 4.2.6):
     * their u and v are the extrapolated values (4.82). Works on any number
     * of ranks (clouds within the ghost layer).
     */
    template <int dim>
    class PdUnboundedWave
    {
    public:
      explicit PdUnboundedWave(const MPI_Comm comm);

      /**
       * @p notches (2D): segments (a, b); every bond crossing one is broken
       * (Sect. 4.2.7), in the operator and in the energy.
       */
      void
      setup(const Domain<dim>                           &domain,
            const LatticeParameters                     &lattice,
            const ScalarWaveParameters                  &model,
            const WaveTruncation                         boundary,
            const WaveAbcParameters                     &abc,
            const Function<dim>                         &initial,
            const std::vector<std::array<Point<dim>, 2>> &notches = {});

      /** Number of broken bonds of the owned rows (notches, all ranks). */
      std::uint64_t
      n_broken_bonds() const;

      /** One velocity-Verlet step with the absorbing update. */
      void
      advance();

      /**
       * Spectral radius of the linear one-step map of the whole truncated
       * system (near-field Verlet plus the absorbing update): the state
       * (u, v of all nodes, u^{n-1}, v^{n-1} of the cloud points; the
       * acceleration is L u - 2 d v) is mapped column by column through
       * advance() and the eigenvalues of the dense matrix are computed by
       * LAPACK. Serial only and at most @p max_size state entries
       * (ParameterError otherwise); the solver state is restored. The number
       * of eigenvalues with modulus > 1 + 1e-8 goes to @p n_unstable and the
       * eigenvalue of largest modulus to @p dominant if given.
       */
      double
      one_step_spectral_radius(const unsigned int    max_size   = 4000,
                               unsigned int         *n_unstable = nullptr,
                               std::complex<double> *dominant   = nullptr);

      /**
       * The same with the dominant eigenvector (inverse iteration with the
       * dominant eigenvalue) located on the nodes: which absorbing node and
       * which part of the state carry the growing mode.
       */
      WaveSpectralDiagnostics
      spectral_diagnostics(const unsigned int max_size = 4000);

      /** One-line description of absorbing node a and its cloud (guard numbers). */
      std::string
      describe_absorbing_node(const unsigned int a) const;

      /**
       * Wave energy (4.99) of the nodes x_i with @p inside(x_i): 1/2 sum v_i^2 V_i +
       * 1/4 sum_i sum_j k (u_j - u_i)^2 beta V_j V_i (all ranks).
       */
      double
      energy(const std::function<bool(const Point<dim> &)> &inside) const;
      /** u at the node nearest to @p p (all ranks agree). */
      double
      value_at(const Point<dim> &p) const;
      /** (position, u) of the nodes with @p inside(x), gathered on all ranks. */
      std::vector<std::pair<Point<dim>, double>>
      gather(const std::function<bool(const Point<dim> &)> &inside) const;

      double
      time() const
      {
        return t;
      }
      const Discretization<dim> &
      discretization() const
      {
        return disc;
      }
      const EbfWaveAbc<dim> &
      absorbing_boundary() const
      {
        return abc;
      }
      const Vector &
      displacement() const
      {
        return u;
      }
      /** The velocities v^n (the absorbing nodes' extrapolated ones included). */
      const Vector &
      velocity() const
      {
        return v;
      }
      /** The dispersion relation used by the ABC (after setup with absorbing). */
      const WaveDispersion<dim> &
      dispersion() const
      {
        return *relation;
      }
      /** Wall seconds in the ABC update and in the whole of advance(). */
      double abc_seconds = 0., step_seconds = 0.;
      /**
       * Benchmarks only: @p on makes advance() skip all absorbing work (the
       * near field then steps as the free truncation), to time the step
       * without the ABC on the same objects and memory as with it
       * (contrib/benchmarks/abc_benchmark.cc). Switching it off again resumes
       * the ABC from the stale level n-1 of before the skip: timing only.
       */
      void
      set_abc_skipped(const bool on)
      {
        skip_abc = on;
      }
      /** One-step spectral radius computed by setup (0 if not checked). */
      double spectral_radius = 0.;
      /** Total damping rate d + sigma(x_i) of each owned node (the sponge). */
      const std::vector<double> &
      damping_rates() const
      {
        return damping;
      }
      /**
       * The discrete energy of the damped velocity Verlet scheme at the last
       * half step, E^{n+1/2} = 1/2 sum_i (v_i^{n+1/2})^2 V_i + 1/2 a(u^n, u^{n+1})
       * with a(u, w) = 1/2 sum_ij k_ij (u_j - u_i)(w_j - w_i) beta V_i V_j
       * (all ranks; needs one advance()). Without an overwritten layer it is
       * non-increasing for any damping d + sigma >= 0 below the critical
       * step (doc/design.md, session 7). With an overwritten (EBF or
       * first-order) layer the v^{n+1/2} of its nodes is not computed (the
       * operator skips their rows), so the value is then not meaningful.
       */
      double
      half_step_energy() const;

    private:
      /** The dense one-step map (column-major, m x m) of one_step_spectral_radius(). */
      unsigned int
      assemble_one_step_map(const unsigned int max_size, std::vector<double> &map);
      /**
       * Lu = L u (u with current ghosts), minus the broken bonds; with
       * @p all_rows false only on the rows that are not overwritten by the
       * absorbing update (operator_rows): the other rows of Lu (and so of a
       * and v_half) are then stale, and are never read for u or v.
       */
      void
      apply_operator(const bool all_rows = true);
      Discretization<dim>                     disc;
      std::unique_ptr<DiffusionOperator<dim>> op;
      std::unique_ptr<WaveDispersion<dim>>    relation;
      EbfWaveAbc<dim>                         abc;
      Vector                                  u, v, a, Lu;
      std::vector<double>                     u_abc, v_abc;
      /** Levels n, n-1 of u and v at the cloud points (EbfWaveAbc::compute_levels()). */
      typename EbfWaveAbc<dim>::CloudLevels   cloud_levels;
      /**
       * EBF or first-order layer: the owned rows outside it, as ranges
       * (the PD operator skips the overwritten rows), and the broken bonds
       * of these rows.
       */
      std::vector<std::array<unsigned int, 2>>                    operator_rows;
      std::vector<std::tuple<unsigned int, unsigned int, double>> broken_operator_rows;
      std::vector<double>                     bond_kernel_weight;
      /** d + sigma(x_i) per owned node; v^{n-1/2} and u^{n-1} of the last step. */
      std::vector<double>                     damping, v_half, u_prev;
      /** Broken bonds: owned row i, local column j, kernel weight. */
      std::vector<std::tuple<unsigned int, unsigned int, double>> broken;
      /** PML (method "pml"): the band, its weights and memories. */
      PmlBand<dim>                            pml_band;
      double                                  dt = 0., t = 0., d = 0.;
      bool                                    absorbing = false, skip_abc = false;
    };
  } // namespace Abc
} // namespace PeriDEAL

#endif
