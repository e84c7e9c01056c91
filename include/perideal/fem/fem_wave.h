#ifndef perideal_fem_fem_wave_h
#define perideal_fem_fem_wave_h

#include <deal.II/base/function.h>

#include <deal.II/dofs/dof_handler.h>

#include <deal.II/fe/fe_q.h>

#include <deal.II/grid/tria.h>

#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/vector.h>

#include <perideal/abc/ebf_wave_abc.h>

#include <functional>
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
      /** Time step (> 0, below the lumped-mass CFL bound). */
      double time_step = 0.;
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
     * with deal.II FE_Q elements (degree 1 or 2), lumped mass (Gauss-Lobatto
     * quadrature at the support points) and damped velocity Verlet. The
     * truncation boundary is absorbing (EBF, the same Abc::EbfWaveAbc as the
     * PD near field, clouds from the DoF support points), first-order
     * absorbing (Robin term chi int_Gamma (u_t + d u) w, lumped), or
     * homogeneous Dirichlet. Serial.
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

      /** One damped velocity-Verlet step. */
      void
      advance();

      /** E = 1/2 int (u_t^2 + chi^2 |grad u|^2) over the cells whose centre satisfies @p inside (4.99). */
      double
      energy(const std::function<bool(const Point<dim> &)> &inside) const;
      /** u at @p p. */
      double
      value_at(const Point<dim> &p) const;
      /** Largest stable time step 2/sqrt(lambda_max) (Gershgorin bound of M^-1 K chi^2). */
      double
      critical_time_step() const;

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

    private:
      FE_Q<dim>                  fe;
      DoFHandler<dim>            dof_handler;
      SparsityPattern            sparsity;
      SparseMatrix<double>       stiffness;
      dealii::Vector<double>     mass, boundary_mass, u, v, a, Ku;
      std::vector<unsigned int>  boundary_dofs;
      Abc::EbfWaveAbc<dim>       abc;
      std::vector<double>        u_old, v_old, u_abc, v_abc;
      WaveBoundary               type;
      double                     chi, d, dt, t = 0.;
    };
  } // namespace Fem
} // namespace PeriDEAL

#endif
