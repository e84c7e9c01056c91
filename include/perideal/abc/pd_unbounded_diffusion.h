#ifndef perideal_abc_pd_unbounded_diffusion_h
#define perideal_abc_pd_unbounded_diffusion_h

#include <deal.II/base/bounding_box.h>
#include <deal.II/base/function.h>

#include <perideal/abc/ebf_diffusion_abc.h>
#include <perideal/discretization/discretization.h>
#include <perideal/models/diffusion.h>

#include <functional>
#include <memory>

namespace PeriDEAL
{
  namespace Abc
  {
    /** How the truncation boundary of a near field is treated. */
    enum class TruncationBoundary
    {
      /** The EBF absorbing boundary (Dirichlet values from the clouds). */
      absorbing,
      /** Nothing: homogeneous Neumann (free PD surface / natural FEM BC). */
      neumann
    };

    /**
     * PD diffusion near field on a truncated domain, marched with explicit
     * forward Euler (3.4) through the DiffusionOperator, with the EBF
     * absorbing boundary on the nodes within delta_L of the truncation
     * boundary (dissertation Sect. 4.1.2, 002 Algorithm 1). The domain must
     * have a signed distance (box, ball). Works on any number of ranks:
     * clouds use the node partitioner's ghosts (d_inf <= delta is required,
     * which every ghost layer covers).
     *
     * With a corrosion model (Model/Type = corrosion, dissertation
     * Sect. 4.1.5) the near field is the bi-material body: three bond
     * micro-diffusivities chosen by the phases of the end points and the
     * phase rule (2.79) after every step. The absorbing nodes must lie in
     * the electrolyte, whose far field is linear diffusion with the liquid
     * diffusivity: the ABC modes use D_liq (local) or the kernel with
     * kappa_liq (nonlocal).
     */
    template <int dim>
    class PdUnboundedDiffusion
    {
    public:
      PdUnboundedDiffusion(const MPI_Comm comm);

      /** Predicate on positions (energy regions). */
      using Region = std::function<bool(const Point<dim> &)>;

      /**
       * Build the lattice, the operator and (for @p boundary absorbing) the
       * clouds; set C = @p initial. @p time_step must satisfy the operator's
       * Gershgorin bound. For corrosion the nodes with C >= C_sat start
       * solid (as in DiffusionSolver); a solid absorbing node is a
       * ParameterError.
       */
      void
      setup(const Domain<dim>              &domain,
            const LatticeParameters        &lattice,
            const DiffusionModelParameters &model,
            const double                    time_step,
            const TruncationBoundary        boundary,
            const EbfParameters            &abc,
            const Function<dim>            &initial);

      /** One forward Euler step with the absorbing update. */
      void
      advance();

      /** Pi = sum C_i^2 V_i over the nodes inside @p region (all ranks). */
      double
      energy(const BoundingBox<dim> &region) const;

      /** Pi = sum C_i^2 V_i (eq. 48 of 002) over the nodes with @p inside(x). */
      double
      energy(const Region &inside) const;

      /** sum C_i V_i over the nodes with @p inside(x). */
      double
      mass(const Region &inside) const;

      /** Volume of the solid nodes (0 for linear diffusion). */
      double
      solid_volume() const;

      /**
       * Pi over the near field Omega_N without the absorbing layer (all
       * nodes for Neumann truncation).
       */
      double
      near_field_energy() const;

      /** Current time. */
      double
      time() const
      {
        return t;
      }
      /** The field (ghosts not necessarily up to date). */
      const Vector &
      solution() const
      {
        return C;
      }
      const Discretization<dim> &
      discretization() const
      {
        return disc;
      }
      /** The phase field (1 solid, 0 liquid); zero for linear diffusion. */
      const Vector &
      phase_field() const
      {
        return phase;
      }
      /** The ABC (empty for Neumann truncation). */
      const EbfDiffusionAbc<dim> &
      absorbing_boundary() const
      {
        return abc;
      }
      /** Wall seconds spent in the ABC update and in the whole of advance(). */
      double abc_seconds = 0., step_seconds = 0.;
      /**
       * Growth per step of the one-step map (phases frozen) measured by the
       * setup's power iteration over the last quarter of its steps (0 if
       * not run). > 1 means an unstable mode; setup throws then.
       */
      double stability_growth = 0.;

    private:
      /**
       * Power iteration of the linear one-step map (forward Euler with the
       * current phases, then the absorbing update) from a pseudo-random
       * vector keyed by node id (rank independent). Sets stability_growth
       * and throws a ParameterError naming the cloud of the absorbing node
       * where the growing vector peaks if the growth exceeds 1.
       */
      void
      check_stability(const unsigned int n_steps);

      /**
       * The "stabilized" fit: rounds of @p n_steps of power iteration from a
       * random start on the nodes @p in_clouds (near the boundary); while
       * the map grows, the clouds carrying the growing vector move halfway
       * from least squares to the monotone fit. Before that, clouds with
       * sum_j |V_j| > @p l1_cap are blended until they are below it.
       */
      void
      stabilize(const unsigned int       n_steps,
                const unsigned int       max_rounds,
                const std::vector<bool> &in_clouds,
                const double             l1_cap);

      /**
       * @p n_steps of the one-step map on @p u (normalized every step,
       * ghosts updated at the end); returns the growth per step over the
       * last quarter.
       */
      double
      power_iteration(Vector &u, const unsigned int n_steps) const;

      /** The pseudo-random start keyed by node id (rank independent). */
      void
      random_vector(Vector &u) const;

      Discretization<dim>                   disc;
      std::unique_ptr<DiffusionOperator<dim>> op;
      EbfDiffusionAbc<dim>                  abc;
      Vector                                C, rate, phase;
      std::vector<double>                   boundary_values;
      double                                dt = 0., t = 0.;
      DiffusionModelParameters              model_parameters;
      /** Per owned node: in the absorbing layer. */
      std::vector<bool> absorbing;
    };
  } // namespace Abc
} // namespace PeriDEAL

#endif
