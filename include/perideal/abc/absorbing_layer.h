#ifndef perideal_abc_absorbing_layer_h
#define perideal_abc_absorbing_layer_h

#include <deal.II/base/tensor.h>

#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>

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
  } // namespace Abc
} // namespace PeriDEAL

#endif
