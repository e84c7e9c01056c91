#include <perideal/abc/absorbing_layer.h>
#include <perideal/base/exceptions.h>

#include <cmath>

namespace PeriDEAL
{
  namespace Abc
  {
    template <int dim>
    void
    find_absorbing_layer(const Discretization<dim>   &disc,
                         const Domain<dim>           &domain,
                         const double                 layer,
                         const double                 cloud_radius,
                         std::vector<unsigned int>   &nodes,
                         std::vector<Tensor<1, dim>> &normals)
    {
      const auto  &lattice = disc.parameters();
      const double dx      = lattice.dx;
      check_parameter(cloud_radius <= lattice.delta + 0.5 * dx, "Absorbing boundary/Cloud radius",
                      cloud_radius, "<= delta + dx/2 (clouds must lie within the ghost layer)");
      check_parameter(layer >= dx * (1. - 1e-12), "Absorbing boundary/Layer thickness", layer,
                      ">= dx (at least one node layer)");
      const double h = 1e-3 * dx;
      nodes.clear();
      normals.clear();
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          const Point<dim> &x = disc.position[i];
          if (-domain.signed_distance(x) < layer - 1e-8 * dx)
            {
              Tensor<1, dim> n;
              for (unsigned int d = 0; d < dim; ++d)
                {
                  Point<dim> xp = x, xm = x;
                  xp[d] += h;
                  xm[d] -= h;
                  n[d] = domain.signed_distance(xp) - domain.signed_distance(xm);
                }
              nodes.push_back(i);
              normals.push_back(n / n.norm());
            }
        }
    }

    template <int dim>
    std::vector<double>
    sponge_profile(const Discretization<dim> &disc,
                   const Domain<dim>         &domain,
                   const double               sigma_max,
                   const double               w,
                   const double               p,
                   const double               s_in,
                   const double               cloud_radius,
                   const std::function<bool(const Point<dim> &, const Tensor<1, dim> &)> &keep)
    {
      check_parameter(w >= disc.parameters().dx * (1. - 1e-12), "Absorbing boundary/Sponge thickness", w,
                      ">= dx when Sponge damping > 0");
      std::vector<double>         sigma(disc.n_owned(), 0.);
      std::vector<unsigned int>   band;
      std::vector<Tensor<1, dim>> normals;
      find_absorbing_layer(disc, domain, s_in, cloud_radius, band, normals);
      for (unsigned int c = 0; c < band.size(); ++c)
        if (!keep || keep(disc.position[band[c]], normals[c]))
          {
            const double s  = -domain.signed_distance(disc.position[band[c]]);
            sigma[band[c]] = sigma_max * std::pow(std::min(1., (s_in - s) / w), p);
          }
      return sigma;
    }

#define PERIDEAL_INSTANTIATE(dim)                                                              \
  template void find_absorbing_layer<dim>(const Discretization<dim> &, const Domain<dim> &,    \
                                          double, double, std::vector<unsigned int> &,         \
                                          std::vector<Tensor<1, dim>> &);                      \
  template std::vector<double> sponge_profile<dim>(                                            \
    const Discretization<dim> &, const Domain<dim> &, double, double, double, double, double,  \
    const std::function<bool(const Point<dim> &, const Tensor<1, dim> &)> &);
    PERIDEAL_INSTANTIATE(1)
    PERIDEAL_INSTANTIATE(2)
    PERIDEAL_INSTANTIATE(3)
#undef PERIDEAL_INSTANTIATE
  } // namespace Abc
} // namespace PeriDEAL
