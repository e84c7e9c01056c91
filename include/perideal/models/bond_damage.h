#ifndef perideal_models_bond_damage_h
#define perideal_models_bond_damage_h

#include <deal.II/base/mpi.h>

#include <perideal/discretization/discretization.h>

#include <cstdint>
#include <vector>

namespace PeriDEAL
{
  /**
   * Bookkeeping shared by every model with irreversible bond breaking
   * (bond-based PMB, LPS): one broken flag per CSR bond of the owned rows.
   */
  namespace BondDamage
  {
    /**
     * Damage (2.36) 1 - sum mu beta V / sum beta V of the owned nodes, with
     * the quadrature weights of the Neighborhood's table layout.
     */
    template <int dim>
    void
    compute_damage(const Discretization<dim>        &disc,
                   const std::vector<std::uint8_t> &broken_flag,
                   Vector                          &phi)
    {
      const auto &nb = disc.neighborhood;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          const std::uint64_t begin = nb.row_start[i];
          const double       *w     = nb.bond_weight.data() + nb.table_start[i];
          double              all = 0., intact = 0.;
          for (std::uint64_t b = begin; b < nb.row_start[i + 1]; ++b)
            {
              all += w[b - begin];
              if (!broken_flag[b])
                intact += w[b - begin];
            }
          phi.local_element(i) = all > 0. ? 1. - intact / all : 0.;
        }
    }

    /** Global number of broken bond copies (each counted once per owned row). */
    inline std::uint64_t
    count_broken(const std::vector<std::uint8_t> &broken_flag, const MPI_Comm comm)
    {
      std::uint64_t n = 0;
      for (const auto f : broken_flag)
        n += f;
      return dealii::Utilities::MPI::sum(n, comm);
    }
  } // namespace BondDamage
} // namespace PeriDEAL

#endif
