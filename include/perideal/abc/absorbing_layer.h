#ifndef perideal_abc_absorbing_layer_h
#define perideal_abc_absorbing_layer_h

#include <deal.II/base/tensor.h>

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>

#include <array>
#include <functional>
#include <vector>

namespace PeriDEAL
{
  namespace Abc
  {
    using namespace dealii;

    /**
     * The absorbing nodes of a PD near field: the owned nodes closer than
     * @p layer (delta_L) to the truncation boundary, with the outward normal
     * (the gradient of the signed distance) at each. Shared by the diffusion
     * and wave ABCs. Throws a ParameterError if the layer is thinner than
     * one node layer or the clouds (@p cloud_radius) reach beyond the ghost
     * layer (delta + dx/2).
     */
    template <int dim>
    void
    find_absorbing_layer(const Discretization<dim>   &disc,
                         const Domain<dim>           &domain,
                         const double                 layer,
                         const double                 cloud_radius,
                         std::vector<unsigned int>   &nodes,
                         std::vector<Tensor<1, dim>> &normals);

    /**
     * Extra damping rate of a sponge per owned node: sigma_max
     * min(1, (s_in - s)/w)^p at depth s < s_in (distance to the truncation
     * boundary), 0 elsewhere and where @p keep (position, outward normal)
     * is false. Throws ParameterError ("Absorbing boundary/Sponge thickness")
     * if w < dx. Shared by the scalar and elastic PD wave drivers.
     */
    template <int dim>
    std::vector<double>
    sponge_profile(const Discretization<dim> &disc,
                   const Domain<dim>         &domain,
                   const double               sigma_max,
                   const double               w,
                   const double               p,
                   const double               s_in,
                   const double               cloud_radius,
                   const std::function<bool(const Point<dim> &, const Tensor<1, dim> &)> &keep = {});

    /**
     * The band of a PD perfectly matched layer (doc/design.md, sessions 8
     * and 9), shared by the scalar (PdUnboundedWave) and the elastic
     * (PdUnboundedElastic) wave drivers. The PML is the outermost @p w of
     * the near field, with sigma = sigma_max (rho/w)^p at the distance
     * rho = w - depth into it. The band holds every owned node within
     * w + delta of the truncation boundary (its bonds may reach into the
     * PML) and per bond the normal weight g = (n . xi/|xi|)^2 >= 0 (n the
     * outward normal at the node) times the bond stiffness k_ij, the decay
     * exp(-sigma_ij dt) with sigma_ij the mean of sigma along the bond, and
     * one memory m_ij of the bond's scalar difference x_ij; per node the
     * decay exp(-sigma_i dt) and one memory per component.
     *
     * Scalar field (1 component): x_ij = u_j - u_i and the normal force
     * sum_j g k x_ij. Vector field (dim components, bond-based PD): x_ij =
     * e . (u_j - u_i) with e = xi/|xi| and the force sum_j g k x_ij e. In
     * the frequency domain each x_ij is divided by s_ij = 1 + i sigma_ij/omega
     * and the sum by s_i; in time x/s = x - m with m' + sigma m = sigma x,
     * advanced by the exponential rule. Nothing is overwritten; rows are
     * owned, so the result does not depend on the partition.
     */
    template <int dim>
    class PmlBand
    {
    public:
      /**
       * Build the band. @p bond_stiffness holds k per entry of the
       * Neighborhood bond tables (row i uses the slice from table_start[i]).
       * Throws ParameterError naming "Absorbing boundary/PML damping"
       * (sigma_max > 0), "PML thickness" (w >= 2 dx) or "PML exponent"
       * (p >= 1). The memories start at zero (no history before t = 0).
       */
      void
      reinit(const Discretization<dim> &disc,
             const Domain<dim>         &domain,
             const std::vector<double> &bond_stiffness,
             const double               sigma_max,
             const double               w,
             const double               p,
             const double               time_step,
             const unsigned int         n_components);

      /** Remove the band (no PML). */
      void
      clear();

      bool
      empty() const
      {
        return nodes.empty();
      }

      /**
       * Add the stretching correction -(sum_j g k m_ij [e] + n_i) to the
       * force @p force of the band nodes, first advancing the memories to
       * the current displacement @p u (ghosts valid) if @p update. The
       * first n_components entries of @p u and @p force are used.
       */
      void
      apply(const bool                            update,
            const std::array<const double *, dim> &u,
            const std::array<double *, dim>       &force);

      /** Number of band nodes with depth < w (the PML proper), this rank. */
      unsigned int n_pml_nodes = 0;
      unsigned int n_components = 1;
      /** Band nodes (local), CSR of their bonds: columns, g k, exp(-sigma_ij dt). */
      std::vector<unsigned int> nodes, start, col;
      std::vector<double>       weight, bond_decay;
      /** Unit bond vectors (dim per bond, vector fields only). */
      std::vector<double> direction;
      /** exp(-sigma_i dt) per band node. */
      std::vector<double> node_decay;
      /** The state: m_ij per bond, n_i per band node and component. */
      std::vector<double> bond_memory, node_memory;
    };
  } // namespace Abc
} // namespace PeriDEAL

#endif
