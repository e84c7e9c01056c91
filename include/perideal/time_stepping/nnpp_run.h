#ifndef perideal_time_stepping_nnpp_run_h
#define perideal_time_stepping_nnpp_run_h

#include <deal.II/base/parameter_handler.h>

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/models/nnpp.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  /**
   * A parameter-file NNPP run (`Problem = nnpp` of the perideal driver):
   * Geometry, Discretization, the model and run entries of the subsection
   * "NNPP" (NnppParameters plus initial data, boundary potential, end time)
   * and the Output entries shared with the diffusion runs.
   */
  template <int dim>
  struct NnppRunParameters
  {
    std::shared_ptr<Domain<dim>> domain;
    LatticeParameters            lattice;
    NnppParameters               model;
    /** C_k(x, 0), one muparser expression in x, y, z per species. */
    std::vector<std::string> initial_concentrations;
    /** Solid where > 0 (x, y, z); empty: C_phase >= C_sat if a phase species is set, else liquid. */
    std::string initial_phase;
    /** phi on the volume-constraint layer, expression in x, y, z, t. */
    std::string boundary_potential = "0";
    /** C_k on the layer for "Species boundary = dirichlet", one expression per species. */
    std::vector<std::string> boundary_concentrations;
    /** Constants usable in the expressions ("a=1, b=2"). */
    std::string constants;
    double      end_time = 1.;

    std::string  output_directory     = "output";
    unsigned int snapshot_interval    = 0; ///< steps between VTU snapshots (0: first and last)
    unsigned int time_series_interval = 1; ///< steps between CSV rows

    /**
     * Add the run entries to the subsection "NNPP" (the model entries are
     * NnppParameters::declare_parameters(); Geometry, Discretization and
     * Output are declared by DiffusionRunParameters).
     */
    static void
    declare_parameters(ParameterHandler &prm);
    /** Read and validate; throws ParameterError naming the entry. */
    void
    parse_parameters(ParameterHandler &prm);
  };

  /** One row of the NNPP time series. */
  struct NnppDiagnostics
  {
    double              time = 0.;
    std::vector<double> amount; ///< sum_i V_i C_k,i over the body, per species
    double              solid_volume = 0.;
    double              max_abs_phi  = 0.;
  };

  /**
   * Run NNPP from @p parameters: VTU snapshots (C_0 ... C_{N-1}, phi, phase)
   * and the CSV time series time_series.csv (time, amount_k, solid volume,
   * max |phi|) in the output directory, unless it is empty. phi in the
   * output is the potential of the concentrations at the output time.
   * Returns the rows of the time series (all ranks). @p on_finish, if set,
   * sees the final state (tutorials and tests compare fields). Collective.
   */
  template <int dim>
  std::vector<NnppDiagnostics>
  run_nnpp(const NnppRunParameters<dim> &parameters,
           const MPI_Comm                comm,
           const bool                    verbose   = true,
           const std::function<void(const Discretization<dim> &, const NnppSolver<dim> &)>
             &on_finish = {});
} // namespace PeriDEAL

#endif
