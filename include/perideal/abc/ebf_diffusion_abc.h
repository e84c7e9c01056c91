#ifndef perideal_abc_ebf_diffusion_abc_h
#define perideal_abc_ebf_diffusion_abc_h

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>
#include <deal.II/base/types.h>

#include <perideal/base/kernel.h>

#include <functional>
#include <string>
#include <vector>

namespace PeriDEAL
{
  using namespace dealii;

  /**
   * Absorbing boundary conditions from exponential basis functions (EBFs)
   * for diffusion-type problems on unbounded domains (dissertation
   * Sect. 4.1, paper 002). Shared by every near field (PD and deal.II FEM).
   */
  namespace Abc
  {
    /**
     * Parameters of the EBF absorbing boundary ("Absorbing boundary"
     * subsection).
     */
    struct EbfParameters
    {
      /** n_k: wave numbers k_m = -m Delta k / n_k, m = 1..n_k (4.25). */
      unsigned int n_wave_numbers = 20;
      /** n_phi: directions phi_l equally spaced in [0, pi/2] (2D), or per
       * spherical angle (3D). Ignored in 1D. */
      unsigned int n_directions = 5;
      /**
       * Delta k of (4.25); 0 selects 1/(8 d_inf) in 1D, 2/d_inf in 2D/3D
       * (empirical, see the .cc), and 1/d_inf with the sink fit in 2D/3D
       * (D Delta k^2 = D/d_inf^2: no mode faster than diffusion across the
       * cloud).
       */
      double wave_number_range = 0.;
      /** Cloud radius d_inf. */
      double cloud_radius = 0.25;
      /** "local" (4.9) or "nonlocal" (4.13)/(4.15), the latter by quadrature. */
      std::string dispersion = "local";
      /** PD absorbing layer thickness delta_L (0: the horizon). */
      double layer_thickness = 0.;
      /** Stability guard: largest admissible moment-matrix condition number. */
      double max_condition_number = 1e12;
      /** Stability guard: largest admissible max-norm of an updating vector. */
      double max_update_norm = 2.;
      /**
       * How V is fitted to the modes. "least squares": V = Psi(dt) M_G^+
       * (4.31). "monotone": the same least-squares fit restricted to V_j >= 0,
       * sum_j V_j = 1 (the constant far field is kept exactly). With a
       * monotone near field (forward Euler at dt <= 1 / max row sum) every
       * row of the one-step map is then a convex combination, so
       * max_i |C_i| cannot grow: stable for every cloud shape. "sink"
       * (Imposed = value): nonnegative least squares without the equality,
       * V_j >= 0 and sum_j V_j <= 1 (scaled down if the fit exceeds 1): the
       * same max principle, but the value can fall below every value of its
       * cloud, which a convex combination cannot (a curved boundary whose
       * values rise inward while they fall in time). A constant far field
       * is not preserved (sum_j V_j < 1 drains it).
       */
      std::string fit = "least squares";
      /**
       * "bounded" fit: least squares with sum_j V_j = 1 and
       * sum_j |V_j| <= 1 + l1_excess (0 gives the monotone fit; the bound
       * limits the negative weights that extrapolation needs).
       */
      double l1_excess = 0.5;
      /**
       * What the clouds give the near field. "value": the absorbing value
       * at t^{n+1} (4.31), imposed as a Dirichlet value. "normal
       * derivative" (FEM, forward Euler with lumped mass): the outward
       * normal derivative at t^n, fitted to d psi/dn(x_i) = k d.n of the
       * modes (and 0 for the constant), which enters the boundary DoF's own
       * FEM row as the flux D dC/dn (a Neumann condition from the EBFs).
       * With the monotone fit dC/dn = sum_{j != i} P_j (C_j - C_i) - q C_i,
       * P_j, q >= 0 (nonnegative least squares): the row stays an M-matrix
       * row with a sink (a Robin-type condition), so that, unlike a convex
       * combination, the boundary value can fall below its cloud's.
       */
      std::string imposed = "value";
      /**
       * Imposed = "half derivative" (FEM, forward Euler with lumped mass):
       * the sum of the principal curvatures of the truncation boundary
       * (2/R on a sphere of radius R, 1/R on a circle, 0 on flat faces).
       * The flux is dC/dn = -(curvature/2) C - D^{-1/2} d^{1/2}C/dt^{1/2}
       * at the boundary DoF itself: the relation every planar EBF mode
       * exp(k n.x + D k^2 t) satisfies (dpsi/dn = k psi, d^{1/2}psi/dt^{1/2}
       * = sqrt(D) |k| psi), with the curvature term that is exact for the
       * outgoing monopole in 3D (exp(-sqrt(s/D) r)/r in Laplace space) and
       * its leading term in 2D. No clouds: the "normal derivative" form
       * replaces the half derivative by the modes' mean rate |k|, a Robin
       * constant set by Delta k; here the rate follows the field's history.
       */
      double boundary_curvature = 0.;
      /**
       * Imposed = "half derivative" (FEM): instead of boundary_curvature,
       * the curvature per boundary DoF estimated from the mesh
       * (Fem::NearFieldLayout::curvatures, clipped at 0).
       */
      bool curvature_from_mesh = false;
      /**
       * Imposed = "half derivative" (FEM): how the Gruenwald-Letnikov
       * history is summed (Abc::HalfDerivativeHistory). "exact": every
       * past level, O(n) per step and boundary DoF. "sum of exponentials":
       * the last half_derivative_exact_steps levels exactly, the older ones
       * by a sum of exponentials of the weights with relative accuracy
       * half_derivative_accuracy over half_derivative_horizon steps, O(1)
       * per step (92 exponentials at 1e-10, 5 exact steps, 1e6 steps).
       */
      std::string half_derivative_history = "sum of exponentials";
      /** "sum of exponentials": relative accuracy of the weights, 1e-13 .. 1e-3. */
      double half_derivative_accuracy = 1e-10;
      /** "sum of exponentials": the most recent levels summed exactly, 0 .. 1000. */
      unsigned int half_derivative_exact_steps = 5;
      /** "sum of exponentials": steps over which the accuracy holds (beyond: absolute error below accuracy |g_horizon| per weight). */
      double half_derivative_horizon = 1e6;
      /** "bounded" fit: V_j >= -lower_bound (a negative value: no bound). */
      double lower_bound = -1.;
      /**
       * "stabilized" fit (PD near field): V = (1 - theta) V_ls + theta V_mono
       * per cloud, theta = 0 (least squares) except on the clouds that carry
       * a growing mode of the one-step map, found by the setup's power
       * iteration, where theta moves halfway to 1 per round. At most this
       * many rounds.
       */
      unsigned int max_stabilization_rounds = 60;
      /**
       * Optional guard for the least-squares fit: largest admissible
       * sum_j |V_j| (the infinity norm of an absorbing row of the one-step
       * map; <= 1 is sufficient for stability, not necessary: off by
       * default).
       */
      double max_update_l1 = 1e10;
      /**
       * PD near field: steps of the power iteration of the one-step map
       * run at setup (0: none). Growth stops the setup with a
       * ParameterError naming the cloud where the growing mode lives.
       */
      unsigned int stability_check_steps = 200;
      /**
       * Relative singular-value cutoff of M_G^+ for the least-squares and
       * stabilized fits (LAPACK's rcond: singular values below this times
       * the largest are dropped; 0: Eigen's rank threshold of the complete
       * orthogonal decomposition).
       */
      double pseudo_inverse_tolerance = 0.;
      /**
       * "value" (4.31): V = Psi(0, dt) M_G^+. "increment" (least squares or
       * stabilized, Imposed = value): the fit extrapolates the change over
       * one step, V = e_i + (Psi(0, dt) - Psi(0, 0)) M_G^+, so that
       * C_i^{n+1} = C_i^n + W . G^n with sum_j W_j = 0 for a constant
       * field, W -> 0 as dt -> 0 even under a cut pseudo-inverse. Identical
       * to "value" when M_G M_G^+ = I (as many retained singular values as
       * cloud points). W is signed, so the boundary value can fall below
       * its whole cloud, which no convex combination can.
       */
      std::string fit_form = "value";
      /**
       * Curved modes (2D/3D, cloud fits): the radius rho of the outgoing
       * fronts at the boundary (0: plane modes exp(k d.x), the source). With
       * rho > 0 every mode is evaluated in the coordinates about the centre
       * x_i - rho n, s = (r - rho) n + rho theta t (r the distance to the
       * centre, theta the angle from n, t the tangential direction), times
       * the amplitude (rho/r)^{(dim-1)/2}: the normal modes are then the
       * exact outgoing spherical solutions (rho/r) exp(k (r - rho) + D k^2 t)
       * in 3D and their WKB form sqrt(rho/r) exp(k (r - rho)) in 2D
       * (e.g. rho = R on a ball near field centred at the source).
       */
      double curvature_radius = 0.;

      static void
      declare_parameters(ParameterHandler &prm);
      /** The caller has entered "Absorbing boundary". */
      void
      parse_parameters(ParameterHandler &prm);
    };

    /**
     * Dispersion relation omega(k) of the real far-field modes
     * psi = exp(k n.x + omega t): local omega = D k^2 (4.9), or the nonlocal
     * PD relation (4.13) omega = integral over the horizon of
     * J(|xi|) (exp(k n.xi) - 1), which is isotropic, so that the angular
     * integral is closed-form (1D: 2 (cosh(kr) - 1), 2D: 2 pi (I_0(kr) - 1),
     * 3D: 4 pi (sinh(kr)/(kr) - 1)) and only the radial one is done by
     * Gauss quadrature.
     */
    class DiffusionDispersion
    {
    public:
      /** omega = D k^2. */
      static DiffusionDispersion
      local(const double diffusivity);
      /** The PD relation of @p kernel (its constant is kappa). */
      static DiffusionDispersion
      nonlocal(const ScalarKernel &kernel);

      /** omega(k). */
      double
      operator()(const double k) const
      {
        return omega(k);
      }
      /** The local diffusivity the relation tends to as k -> 0. */
      double
      diffusivity() const
      {
        return local_diffusivity;
      }
      /** "local" or "nonlocal". */
      std::string name;

    private:
      std::function<double(double)> omega;
      double                        local_diffusivity = 1.;
    };

    /** Summary of the clouds after setup (global over all ranks). */
    struct CloudStatistics
    {
      types::global_dof_index n_absorbing = 0;
      unsigned int            min_cloud_size = 0, max_cloud_size = 0;
      /** Largest condition number (sigma_max / smallest retained sigma) of M_G. */
      double max_condition_number = 0.;
      /** Largest max-norm of an updating vector V. */
      double max_update_norm = 0.;
      /** Largest sum_j |V_j| (the amplification bound of one update). */
      double max_update_l1 = 0.;
      /** Largest relative residual |V M_G - Psi(dt)| / |Psi(dt)| of the fit. */
      double max_fit_residual = 0.;
      /** "stabilized" fit: clouds with theta > 0, the largest theta, rounds. */
      types::global_dof_index n_blended = 0;
      double                  max_blend = 0.;
      unsigned int            stabilization_rounds = 0;
      /** Delta k used and the bound (4.33) 1/sqrt(D dt). */
      double wave_number_range = 0., wave_number_bound = 0.;
    };

    /**
     * The EBF absorbing boundary for diffusion: for every absorbing node x_i
     * (owned by this rank) a cloud of the available points within d_inf
     * (x_i first, then by global id, so that the result does not depend on
     * the partition), a local frame rotated so that the first
     * quadrant/octant faces the exterior (4.24), the real mode set obeying
     * the infinity condition (4.22), the moment matrix M_G (4.28), its
     * Moore-Penrose inverse (Eigen complete orthogonal decomposition) and
     * the updating vector V = Psi(0, dt) M_G^+ (4.31). Per step the new
     * absorbing value is one dot product V . G^n.
     */
    template <int dim>
    class EbfDiffusionAbc
    {
    public:
      /**
       * Precompute everything. @p points / @p ids: every point available on
       * this rank (owned and ghost, in the local numbering of the field
       * vectors) with its global id. @p absorbing: local indices of the owned
       * absorbing points, @p outward_normals their outward normals.
       * Throws ParameterError if Delta k violates (4.33) or a cloud is
       * unusable (too few points, condition number or |V| above the guards).
       */
      void
      reinit(const std::vector<Point<dim>>              &points,
             const std::vector<types::global_dof_index> &ids,
             const std::vector<unsigned int>            &absorbing,
             const std::vector<Tensor<1, dim>>          &outward_normals,
             const DiffusionDispersion                  &dispersion,
             const double                                time_step,
             const EbfParameters                        &parameters,
             const MPI_Comm                              comm);

      /**
       * values[a] = V_a . G^n for absorbing node a, from the point values
       * @p u (local numbering, ghosts included and up to date).
       */
      void
      compute(const double *u, std::vector<double> &values) const
      {
        values.resize(absorbing.size());
        for (unsigned int a = 0; a < absorbing.size(); ++a)
          {
            double s = 0.;
            for (unsigned int c = cloud_start[a]; c < cloud_start[a + 1]; ++c)
              s += update_vector[c] * u[cloud_index[c]];
            values[a] = s;
          }
      }

      /** Local indices of the owned absorbing points. */
      const std::vector<unsigned int> &
      absorbing_points() const
      {
        return absorbing;
      }
      /** Cloud (local indices) and updating vector of absorbing point a. */
      std::vector<std::pair<unsigned int, double>>
      cloud(const unsigned int a) const;
      /**
       * "stabilized" fit: set the blend theta of cloud a, V = (1 - theta)
       * V_ls + theta V_mono (the statistics' blend fields are the caller's).
       */
      void
      set_blend(const unsigned int a, const double theta);
      /** The blend theta of cloud a (0 unless "stabilized"). */
      double
      blend(const unsigned int a) const
      {
        return theta.empty() ? 0. : theta[a];
      }

      /**
       * The "stabilized" fit's blending, shared by every near field. First
       * each cloud with sum_j |V_j| > @p l1_cap takes the smallest theta of
       * 0, 1/2, 3/4, ..., 1 that brings it below the cap. Then at most
       * @p max_rounds rounds: @p one_step_growth() measures the growth per
       * step of the near field's one-step map (with the current blend) and
       * leaves a growing iterate behind, read through @p iterate(local
       * index, ghosts included); while the growth exceeds @p threshold, every
       * cloud whose points carry at least a tenth of the iterate's peak
       * (over all ranks) moves halfway to the monotone fit (theta = 1 -
       * 2^-r; the last step goes to 1). Ends by recomputing the statistics'
       * blend and norm fields for the vectors in use.
       */
      void
      stabilize(const double                                 l1_cap,
                const unsigned int                           max_rounds,
                const double                                 threshold,
                const std::function<double()>               &one_step_growth,
                const std::function<double(unsigned int)>   &iterate,
                const MPI_Comm                               comm);
      /** Statistics of all clouds. */
      CloudStatistics &
      statistics()
      {
        return stats;
      }
      /** Statistics of all clouds. */
      const CloudStatistics &
      statistics() const
      {
        return stats;
      }

      /**
       * The local frame R with R n = (1,..,1)/sqrt(dim) (4.24 in 2D; 1D: the
       * outward axis; 3D: the first octant faces the exterior).
       */
      static Tensor<2, dim>
      local_frame(const Tensor<1, dim> &outward_normal);
      /** Unit direction vectors of the modes in the local frame (4.22). */
      static std::vector<Tensor<1, dim>>
      mode_directions(const unsigned int n_directions);

    private:
      std::vector<unsigned int> absorbing;
      std::vector<unsigned int> cloud_start;
      std::vector<unsigned int> cloud_index;
      std::vector<double>       update_vector;
      /** "stabilized" fit: the two fits and the blend per cloud. */
      std::vector<double>       update_ls, update_monotone, theta;
      CloudStatistics           stats;
    };
  } // namespace Abc
} // namespace PeriDEAL

#endif
