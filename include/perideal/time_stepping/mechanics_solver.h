#ifndef perideal_time_stepping_mechanics_solver_h
#define perideal_time_stepping_mechanics_solver_h

#include <deal.II/base/function_parser.h>
#include <deal.II/base/parameter_handler.h>

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/models/bond_based.h>
#include <perideal/time_stepping/velocity_verlet.h>

#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  /**
   * Everything an explicit bond-based PD run reads from its parameter file:
   * geometry and discretization (shared with the diffusion runs), the
   * bond-based model (Model/Bond-based), density, initial velocity, body
   * force, prescribed-velocity regions and pre-cracks (Mechanics), time
   * stepping and output.
   */
  template <int dim>
  struct MechanicsRunParameters
  {
    std::shared_ptr<Domain<dim>> domain;
    LatticeParameters            lattice;
    BondBasedModelParameters     model;
    double                       density = 1.;
    std::string                  initial_velocity, body_force;
    /** (region level set {f <= 0}, velocity expressions "vx; vy[; vz]") */
    std::vector<std::pair<std::string, std::string>> prescribed_velocities;
    /** 2D pre-crack segments (a, b). */
    std::vector<std::pair<Point<dim>, Point<dim>>> precracks;
    double       time_step = 0., end_time = 1.;
    std::string  output_directory = "output";
    unsigned int snapshot_interval = 0, time_series_interval = 1;
    double       progress_interval = 10.;

    /** Declare the mechanics entries (Geometry etc. are declared elsewhere). */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate; throws ParameterError naming the entry. */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /**
   * Dynamic bond-based PD (PMB/GPBM with brittle fracture, or linearized)
   * with velocity Verlet: the run behind `perideal` with
   * `Problem = mechanics`. Writes displacement, velocity and damage to
   * VTU and kinetic/strain energy, broken bonds and maximum damage to the
   * CSV time series.
   */
  template <int dim>
  class MechanicsSolver
  {
  public:
    MechanicsSolver(const MPI_Comm comm, const MechanicsRunParameters<dim> &parameters);
    ~MechanicsSolver();

    /** Build the lattice, model, integrator and initial state. */
    void
    setup();

    /** March to the end time (at most @p max_steps steps of this call). */
    void
    run(const unsigned int max_steps = std::numeric_limits<unsigned int>::max());

    /** @name State */
    /** @{ */
    const Discretization<dim> &
    discretization() const
    {
      return disc;
    }
    const BondBasedOperator<dim> &
    model() const
    {
      return *op;
    }
    const VelocityVerlet<dim> &
    integrator() const
    {
      return *verlet;
    }
    /** Kinetic + strain energy. */
    double
    total_energy() const;
    /** @} */

  private:
    MPI_Comm                                mpi_communicator;
    MechanicsRunParameters<dim>             prm;
    Discretization<dim>                     disc;
    std::unique_ptr<BondBasedOperator<dim>> op;
    std::unique_ptr<VelocityVerlet<dim>>    verlet;
    unsigned int                            total_steps = 0;
  };
} // namespace PeriDEAL

#endif
