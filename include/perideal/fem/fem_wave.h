#ifndef perideal_fem_fem_wave_h
#define perideal_fem_fem_wave_h

#include <deal.II/base/function.h>
#include <deal.II/base/parameter_handler.h>

#include <deal.II/dofs/dof_handler.h>

#include <deal.II/fe/fe_q.h>

#include <deal.II/grid/tria.h>

#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>

#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/fem/near_field.h>

#include <complex>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  namespace Fem
  {
    /** Parameters of the classical FEM viscous scalar wave solver. */
    struct FemWaveParameters
    {
      /** FE_Q degree (1 or 2). */
      unsigned int degree = 1;
      /** Wave speed chi (> 0). */
      double wave_speed = 1.;
      /** Damping d >= 0 of u_tt + 2 d u_t = chi^2 Laplace u. */
      double damping = 0.;
      /** Time step (> 0; velocity Verlet: below the lumped-mass CFL bound). */
      double time_step = 0.;
      /** Lumped (row sums, diagonal) or consistent mass matrix (consistent: scheme Newmark only). */
      bool lumped_mass = true;
      /**
       * "velocity Verlet" (explicit, damped (4.62)) or "Newmark" (implicit
       * average acceleration, beta = 1/4, gamma = 1/2: unconditionally
       * stable for the interior, one Trilinos KLU factorization at setup).
       */
      std::string scheme = "velocity Verlet";
      /**
       * EBF ABC: extrapolate u - u_i^n instead of u at absorbing DoF i, i.e.
       * add (1 - sum_j V_G,j) u_i^n, so that the static state u = const (an
       * exact far-field solution) is kept exactly. The min-norm collocation
       * (4.80) spreads a constant over damped modes and loses O(d dt) of it
       * per step otherwise.
       */
      bool preserve_constants = true;
      /**
       * EBF ABC: v of the absorbing DoFs from V_H (4.82) as in the source
       * (true), or the difference quotient (u^{n+1} - u^n) / dt (false). u
       * does not depend on this choice (boundary velocities enter only V_H);
       * with V_H the closed boundary-velocity recursion grows without bound
       * in E13 (measured), which makes the energy (4.99) meaningless.
       */
      bool extrapolate_velocity = false;
      /**
       * Tangential viscosity of a boundary layer (velocity Verlet only; 0,
       * the default: off, the source's scheme). The force -eta L (M^-1 L)^(o
       * - 1) v, o = layer_order, eta = layer_viscosity chi h^(2 o - 1) (h the
       * node spacing), L the ring Laplacian: sum over the stiffness
       * couplings (i, j) with g_i = g_j = r of sigma_r |K_ij| (e_i - e_j)
       * (e_i - e_j)^T, g the graph distance from the boundary (in stiffness
       * couplings), sigma_r = 1 - (r - r_0) / layer_width on the rings
       * r_0 <= r < r_0 + layer_width, r_0 = 1 when the boundary DoFs are
       * prescribed (EBF, Dirichlet), 0 with the first-order ABC. L is
       * positive semi-definite and couples free DoFs only, so the term only
       * dissipates; it couples DoFs along the boundary only, so a field
       * varying along the normal is not damped at all and a tangentially
       * smooth one as (k_t h)^(2 o). Why: with lumped mass the Q1 scheme has
       * a backward-wave branch at the tangential Nyquist wave number
       * (omega^2 = (10/3 + 2/3 cos(kappa h)) chi^2 / h^2 on a uniform square
       * mesh, omega falling with the normal wave number kappa), on which the
       * EBF extrapolation, outgoing in phase, is incoming in energy: the
       * one-step radius 1.0025 on squares, the dominant eigenvector a
       * tangential sawtooth at the edges (doc/design.md, session 13).
       * layer_viscosity 0.2 (o = 2, width 3) makes the radius 1 on the
       * measured squares (h = 0.5 and 0.25, dt = 0.02; threshold ~0.15).
       */
      double layer_viscosity = 0.;
      /** Width of the viscous layer in DoF rings. */
      unsigned int layer_width = 3;
      /** Order o of the layer operator: 1 (L) or 2 (L M^-1 L, more selective). */
      unsigned int layer_order = 2;

      /**
       * Declare the entries (Degree, Wave speed, Damping, Time step, Lumped
       * mass, Scheme, Preserve constants, Extrapolate velocity, Layer
       * viscosity, Layer width, Layer order) in the current subsection,
       * conventionally "FEM": FemWave's errors name them as FEM/<entry>.
       */
      static void
      declare_parameters(ParameterHandler &prm);
      /** Read the entries declared by declare_parameters(); FemWave checks the ranges. */
      void
      parse_parameters(ParameterHandler &prm);
    };

    /** Treatment of the truncation boundary of the FEM near field. */
    enum class WaveBoundary
    {
      /** EBF ABC (4.82) as time-dependent Dirichlet data on the boundary DoFs. */
      absorbing,
      /** Conventional first-order ABC u_t + chi u_n + d u = 0 (4.63)-(4.75). */
      first_order,
      /** Homogeneous Dirichlet (the extended reference of Sect. 4.2.5). */
      dirichlet
    };

    /**
     * Viscous scalar wave equation u_tt + 2 d u_t = chi^2 Laplace u (2.37)
     * with deal.II FE_Q elements (degree 1 or 2) on a serial or
     * parallel::distributed triangulation (squares, disks, ...): lumped mass
     * with damped velocity Verlet, or lumped/consistent mass with implicit
     * Newmark (average acceleration). The truncation boundary is absorbing
     * (EBF, the same Abc::EbfWaveAbc as the PD near field, clouds from the
     * DoF support points, local frames from the outward normal, u^{n+1} of
     * the boundary DoFs as time-dependent Dirichlet data), first-order
     * absorbing (Robin term chi int_Gamma (u_t + d u) w, lumped), or
     * homogeneous Dirichlet. Cloud DoFs of other ranks are ghosts, so the
     * result does not depend on the number of ranks. On curved boundaries
     * (disks centred at the source) use curved modes,
     * Abc::WaveAbcParameters::curvature_radius = R with n_directions = 0:
     * plane modes are no better than the first-order ABC there
     * (doc/design.md, session 12).
     */
    template <int dim>
    class FemWave
    {
    public:
      FemWave(const Triangulation<dim>      &tria,
              const FemWaveParameters        &parameters,
              const WaveBoundary              boundary,
              const Abc::WaveAbcParameters   &abc,
              const Function<dim>            &initial);

      /** One time step (velocity Verlet or Newmark). */
      void
      advance();

      /** E = 1/2 int (u_t^2 + chi^2 |grad u|^2) over the cells whose centre satisfies @p inside (4.99). */
      double
      energy(const std::function<bool(const Point<dim> &)> &inside) const;
      /** u at @p p. */
      double
      value_at(const Point<dim> &p) const;
      /** Largest stable velocity-Verlet step 2/sqrt(lambda_max) (Gershgorin bound of M_lumped^-1 K chi^2). */
      double
      critical_time_step() const;
      /**
       * Spectral radius of the linear one-step map of the truncated system
       * (time integrator plus boundary treatment), the FEM counterpart of
       * Abc::PdUnboundedWave::one_step_spectral_radius: state (u, v, and for
       * Newmark a, of all DoFs, u^{n-1}, v^{n-1} of the cloud points;
       * serial runs only), mapped column by column
       * through advance(), eigenvalues by LAPACK. At most @p max_size state
       * entries (ParameterError otherwise); the state is restored. The number
       * of eigenvalues with modulus > 1 + 1e-8 goes to @p n_unstable.
       */
      double
      one_step_spectral_radius(const unsigned int    max_size   = 4000,
                               unsigned int         *n_unstable = nullptr,
                               std::complex<double> *dominant   = nullptr);
      /**
       * The dispersion relation the EBF ABC uses: "local" chi^2 |k|^2 (4.39),
       * or "discrete": the symbol of the lumped-mass Q1 scheme,
       * sum_j (-chi^2 K_ij / m_i) (1 - cos(k.(x_j - x_i))) from the stiffness
       * row of the DoF nearest the mesh centre (a uniform Cartesian mesh).
       */
      const Abc::WaveDispersion<dim> &
      dispersion() const
      {
        return relation;
      }
      /** Wall seconds in the ABC update and in the whole of advance(). */
      double abc_seconds = 0., step_seconds = 0.;
      /**
       * One-step spectral radius computed by the constructor when the state
       * size is at most WaveAbcParameters::spectral_check_size (0 otherwise).
       */
      double spectral_radius = 0.;

      double
      time() const
      {
        return t;
      }
      const Abc::EbfWaveAbc<dim> &
      absorbing_boundary() const
      {
        return abc;
      }
      const DoFHandler<dim> &
      get_dof_handler() const
      {
        return dof_handler;
      }
      /** DoF layout: support points, ids, boundary DoFs. */
      const NearFieldLayout<dim> &
      layout() const
      {
        return near_field;
      }
      /** The displacement u (owned DoFs, then ghosts). */
      const DistributedVector &
      solution() const
      {
        return u;
      }

    private:
      FE_Q<dim>                      fe;
      DoFHandler<dim>                dof_handler;
      NearFieldLayout<dim>           near_field;
      TrilinosWrappers::SparseMatrix stiffness, mass_matrix, system;
      SolverControl                  solver_control;
      std::unique_ptr<TrilinosWrappers::SolverDirect> solver, mass_solver;
      DistributedVector              mass, boundary_mass, u, v, a, Ku, u_star, v_star, rhs, tmp;
      /** Local indices of the owned boundary DoFs. */
      std::vector<unsigned int>  boundary_dofs;
      Abc::EbfWaveAbc<dim>       abc;
      Abc::WaveDispersion<dim>   relation;
      /** Previous level of the cloud points (local numbering). */
      std::vector<double>        u_old, v_old, u_abc, v_abc;
      /** 1 - V_G . 1 per absorbing DoF (0 without the constant correction). */
      std::vector<double>        constant_defect;
      WaveBoundary               type;
      bool                       extrapolate_velocity, lumped, newmark;
      /** The viscous layer: L, a copy of v and the layer force. */
      bool                           has_layer = false;
      TrilinosWrappers::SparseMatrix layer_matrix;
      DistributedVector              layer_v, layer_force;
      double                     chi, d, dt, t = 0., layer_eta = 0.;
      unsigned int               layer_order = 1;

      /** a from the current u, v (what advance() leaves at every non-boundary DoF). */
      void
      set_acceleration();
      /** rhs = M x (lumped or consistent). */
      void
      apply_mass(const DistributedVector &x, DistributedVector &y) const;
      void
      advance_verlet();
      /** layer_force = eta L (M^-1 L)^(o - 1) v (nothing without a layer). */
      void
      apply_layer_viscosity();
      void
      advance_newmark();
      /** u^{n+1} of the absorbing DoFs from the cloud data of level n, n-1 (then level n becomes n-1). */
      void
      extrapolate_boundary();
    };
  } // namespace Fem
} // namespace PeriDEAL

#endif
