#ifndef perideal_fem_fem_diffusion_h
#define perideal_fem_fem_diffusion_h

#include <deal.II/base/bounding_box.h>
#include <deal.II/base/function.h>
#include <deal.II/base/parameter_handler.h>

#include <deal.II/dofs/dof_handler.h>

#include <deal.II/fe/fe_q.h>

#include <deal.II/grid/tria.h>

#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>

#include <perideal/abc/ebf_diffusion_abc.h>
#include <perideal/abc/half_derivative_history.h>
#include <perideal/abc/pd_unbounded_diffusion.h>
#include <perideal/fem/near_field.h>

#include <memory>

#include <string>

namespace PeriDEAL
{
  namespace Fem
  {
    /** Parameters of the classical FEM diffusion solver. */
    struct FemDiffusionParameters
    {
      /** FE_Q degree (1 or 2). */
      unsigned int degree = 1;
      /** Lumped (Gauss-Lobatto, diagonal) or consistent mass matrix. */
      bool lumped_mass = true;
      /** "forward Euler" or "backward Euler". */
      std::string scheme = "forward Euler";
      /** Diffusivity D of (4.1). */
      double diffusivity = 1.;
      /** Time step. */
      double time_step = 1e-3;

      /**
       * Declare the entries (Degree, Lumped mass, Scheme, Diffusivity, Time
       * step) in the current subsection, conventionally "FEM": FemDiffusion's
       * errors name them as FEM/<entry>.
       */
      static void
      declare_parameters(ParameterHandler &prm);
      /** Read the entries declared by declare_parameters(); FemDiffusion checks the ranges. */
      void
      parse_parameters(ParameterHandler &prm);
    };

    /**
     * Classical diffusion (4.1) C_t = D Laplace C with continuous FE_Q
     * elements on a serial or parallel::distributed triangulation (any
     * GridGenerator mesh: segment, square, disk): M dC/dt + K C = 0 (4.32)
     * marched with forward or backward Euler. The truncation boundary is
     * either natural (homogeneous Neumann) or absorbing: the boundary DoFs
     * are the absorbing nodes of the EBF ABC (local frame from the outward
     * normal), whose values at t^{n+1} (computed from the DoF values at
     * t^n) enter the step as time-dependent Dirichlet rows. Clouds may
     * straddle ranks: their DoFs are ghosts (NearFieldLayout), so the
     * result does not depend on the number of ranks. Systems are
     * factorized once (Trilinos Amesos KLU); with lumped mass the explicit
     * step needs no solve.
     */
    template <int dim>
    class FemDiffusion
    {
    public:
      FemDiffusion(const Triangulation<dim> &tria, const FemDiffusionParameters &parameters);

      /**
       * Distribute DoFs, assemble M and K, build the ABC (for @p boundary
       * absorbing; local dispersion with D), interpolate @p initial. With
       * EbfParameters::imposed "value" the absorbing DoFs get the EBF values
       * as Dirichlet rows; with "normal derivative" (forward Euler, lumped
       * mass) they keep their FEM rows and the EBF normal derivative enters
       * as the flux D dC/dn (fit "monotone": dC/dn = sum_j P_j (C_j - C_i)
       * - q C_i with P, q >= 0, a Robin-type sink that keeps the row an
       * M-matrix row). With "half derivative" (forward Euler, lumped mass)
       * the boundary DoFs keep their FEM rows with the flux dC/dn =
       * -(kappa/2) C - D^{-1/2} d^{1/2}C/dt^{1/2} of their own history
       * (Gruenwald-Letnikov, the current level implicitly; no clouds and no
       * one-step check, the map has memory; the history exact or by sums of
       * exponentials, EbfParameters::half_derivative_history), and the step
       * must keep the boundary rows nonnegative (ParameterError naming
       * FEM/Time step).
       * The "stabilized" fit blends by
       * Abc::EbfDiffusionAbc::stabilize with this map.
       * Throws ParameterError if the explicit step is unstable, or (absorbing,
       * EbfParameters::stability_check_steps > 0) if the one-step map with
       * the ABC grows (spectral radius above 1 + 1e-5 by
       * arnoldi_spectral_radius(steps / 4, 60)): the ABC extrapolates explicitly
       * over dt, so even backward Euler has a largest admissible time step,
       * which depends on the cloud (no closed form: see
       * doc/design.md, "FEM near field"); the error names FEM/Time step and
       * the largest stable step found by halving and bisection.
       */
      void
      setup(const Abc::TruncationBoundary boundary,
            const Abc::EbfParameters     &abc_parameters,
            const Function<dim>          &initial);

      /** One time step. */
      void
      advance();

      /** Pi = integral of C_h^2 over the cells with centre in @p region. */
      double
      energy(const BoundingBox<dim> &region) const;

      /** max over DoFs inside @p region of |C_h - exact(t)|. */
      double
      max_error(Function<dim> &exact, const BoundingBox<dim> &region) const;

      double
      time() const
      {
        return t;
      }
      /** The solution (owned DoFs, then ghosts; see layout()). */
      const DistributedVector &
      solution() const
      {
        return C;
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
      const Abc::EbfDiffusionAbc<dim> &
      absorbing_boundary() const
      {
        return abc;
      }
      /** Imposed = half derivative: the boundary DoFs' history (EbfParameters::half_derivative_history). */
      const Abc::HalfDerivativeHistory &
      half_derivative_history() const
      {
        return half_history;
      }
      /**
       * Spectral radius of the one-step map C^n -> C^{n+1} (ABC included),
       * by a dense eigenvalue problem (serial, at most @p max_size DoFs);
       * the state is restored afterwards.
       */
      double
      one_step_spectral_radius(const unsigned int max_size = 3000);

      /**
       * Growth per step of the one-step map by @p n_steps steps of the
       * power iteration from a random start on the cloud DoFs (the state is
       * restored afterwards; any number of ranks).
       */
      double
      power_iteration_growth(const unsigned int n_steps);

      /**
       * Spectral radius of the one-step map (ABC included) estimated by
       * Arnoldi: @p n_warm power-iteration steps from the random cloud start
       * of power_iteration_growth(), then @p n_krylov Arnoldi steps (modified
       * Gram-Schmidt, reorthogonalized); the largest Ritz value modulus of
       * the Hessenberg matrix. Any number of ranks; the state is restored.
       */
      double
      arnoldi_spectral_radius(const unsigned int n_warm, const unsigned int n_krylov);
      /** Spectral radius (Arnoldi) measured by the setup's stability check (0: not run). */
      double stability_growth = 0.;

      /** Largest stable forward Euler step 2 / lambda_max(M^-1 K) (power iteration). */
      double critical_time_step = 0.;
      /** Wall seconds in the ABC update and in advance(). */
      double abc_seconds = 0., step_seconds = 0.;

    private:
      /**
       * C = @p n_steps steps of the normalized power iteration from the
       * random cloud start (ghosts updated); returns the growth per step
       * over the last quarter.
       */
      double
      power_iterate(const unsigned int n_steps);
      /** Imposed = half derivative: append C^n of the boundary DoFs to the history; boundary_values = its part sum_{j >= 1} g_j C^{n+1-j} of the half derivative at t^{n+1}. */
      void
      half_derivative_flux();
      /** C = the pseudo-random start on the owned cloud DoFs (seeded by global id), normalized. */
      void
      random_cloud_start();
      /** The state that the stability checks step and then put back. */
      struct SavedState
      {
        DistributedVector C;
        double            t, abc_seconds, step_seconds;
      };
      SavedState
      save_state() const
      {
        return {C, t, abc_seconds, step_seconds};
      }
      void
      restore_state(const SavedState &s)
      {
        C            = s.C;
        t            = s.t;
        abc_seconds  = s.abc_seconds;
        step_seconds = s.step_seconds;
        C.update_ghost_values();
      }
      const Triangulation<dim>      &tria;
      FemDiffusionParameters         prm;
      FE_Q<dim>                      fe;
      DoFHandler<dim>                dof_handler;
      NearFieldLayout<dim>           near_field;
      TrilinosWrappers::SparseMatrix mass, stiffness, system;
      DistributedVector              lumped, boundary_lumped;
      /** Imposed = normal derivative: D (boundary mass) / (lumped mass) of the absorbing DoFs, else 0. */
      DistributedVector              flux_weight;
      /** Imposed = normal derivative: the absorbing DoFs keep their FEM rows and get the EBF flux. */
      bool                           flux_boundary = false;
      /**
       * Imposed = half derivative: the boundary DoFs, their values at the
       * current level and their Gruenwald-Letnikov history.
       */
      bool                           half_derivative = false;
      std::vector<unsigned int>      half_dofs;
      std::vector<double>            half_values;
      Abc::HalfDerivativeHistory     half_history;
      /** Imposed = half derivative: kappa per boundary DoF (given or estimated). */
      std::vector<double>            half_curvature;
      SolverControl                  solver_control;
      std::unique_ptr<TrilinosWrappers::SolverDirect> solver;
      Abc::EbfDiffusionAbc<dim>      abc;
      std::vector<double>            boundary_values;
      /** energy(): cells of the last region, local indices of their DoFs and local mass matrices. */
      mutable BoundingBox<dim>                       energy_region;
      mutable bool                                   energy_cached = false;
      mutable std::vector<std::vector<unsigned int>> energy_dofs;
      mutable std::vector<FullMatrix<double>>        energy_mass;
      DistributedVector                              C, rhs, tmp;
      double                                         t = 0.;
    };
  } // namespace Fem
} // namespace PeriDEAL

#endif
