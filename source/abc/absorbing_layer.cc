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

    template <int dim>
    void
    PmlBand<dim>::clear()
    {
      for (auto *x : {&nodes, &start, &col})
        x->clear();
      for (auto *x : {&weight, &bond_decay, &direction, &node_decay, &bond_memory, &node_memory})
        x->clear();
      n_pml_nodes = 0;
    }

    template <int dim>
    void
    PmlBand<dim>::reinit(const Discretization<dim> &disc,
                         const Domain<dim>         &domain,
                         const std::vector<double> &bond_stiffness,
                         const double               sigma_max,
                         const double               w,
                         const double               p,
                         const double               dt,
                         const unsigned int         components)
    {
      const auto &lattice = disc.parameters();
      check_parameter(sigma_max > 0., "Absorbing boundary/PML damping", sigma_max, "> 0 with method pml");
      check_parameter(w >= 2. * lattice.dx * (1. - 1e-12), "Absorbing boundary/PML thickness", w,
                      ">= 2 dx = " + std::to_string(2. * lattice.dx) + " with method pml");
      check_parameter(p >= 1., "Absorbing boundary/PML exponent", p, ">= 1");
      Assert(components == 1 || components == dim, ExcInternalError());
      clear();
      n_components = components;
      const auto &nb = disc.neighborhood;
      // sigma and its integral Sigma over the distance rho = w - depth.
      const auto rho_of = [&](const Point<dim> &x) { return w + domain.signed_distance(x); };
      const auto sigma  = [&](const double r) { return r > 0. ? sigma_max * std::pow(r / w, p) : 0.; };
      const auto Sigma  = [&](const double r) {
        return r > 0. ? sigma_max * w * std::pow(r / w, p + 1.) / (p + 1.) : 0.;
      };
      // The normal part of each bond is weighted by (n . e)^2 >= 0: the
      // isotropic weights ((dim + 2) (n . e)^2 - 1)/2, which tend to d^2/dn^2
      // exactly, are partly negative and made the layer unstable (design.md).
      std::vector<Tensor<1, dim>> normals;
      find_absorbing_layer(disc, domain, w + lattice.delta, lattice.delta, nodes, normals);
      start.push_back(0);
      for (unsigned int c = 0; c < nodes.size(); ++c)
        {
          const unsigned int i   = nodes[c];
          const double       r_i = rho_of(disc.position[i]);
          // The band must not reach a point without a normal (a ball's centre).
          bool finite = true;
          for (unsigned int d = 0; d < dim; ++d)
            finite = finite && std::isfinite(normals[c][d]);
          check_parameter(finite, "Absorbing boundary/PML thickness", w,
                          "such that w + delta stays off the points where the distance to the "
                          "truncation boundary has no gradient (a ball's centre)");
          n_pml_nodes += r_i > 0. ? 1 : 0;
          node_decay.push_back(std::exp(-sigma(r_i) * dt));
          const double *k = bond_stiffness.data() + nb.table_start[i];
          for (std::uint64_t q = nb.row_start[i]; q < nb.row_start[i + 1]; ++q)
            {
              const unsigned int   j   = nb.col[q];
              const Tensor<1, dim> e   = (disc.position[j] - disc.position[i]) / (disc.position[j] - disc.position[i]).norm();
              const double         r_j = rho_of(disc.position[j]);
              // Mean of sigma along the bond (the stretched bond length).
              const double s_ij = std::abs(r_j - r_i) > 1e-9 * lattice.dx ? (Sigma(r_j) - Sigma(r_i)) / (r_j - r_i) :
                                                                          sigma(r_i);
              // Outside the PML (sigma_i = 0) the node memory stays 0, so a
              // bond with sigma_ij = 0 (memory 0 for ever) adds nothing.
              if (sigma(r_i) == 0. && s_ij == 0.)
                continue;
              col.push_back(j);
              weight.push_back((normals[c] * e) * (normals[c] * e) * k[q - nb.row_start[i]]);
              bond_decay.push_back(std::exp(-s_ij * dt));
              if (n_components > 1)
                for (unsigned int d = 0; d < dim; ++d)
                  direction.push_back(e[d]);
            }
          start.push_back(col.size());
        }
      bond_memory.assign(col.size(), 0.);
      node_memory.assign(nodes.size() * n_components, 0.);
    }

    template <int dim>
    void
    PmlBand<dim>::apply(const bool update, const std::array<const double *, dim> &u,
                        const std::array<double *, dim> &force)
    {
      const unsigned int nc = n_components;
      for (unsigned int c = 0; c < nodes.size(); ++c)
        {
          const unsigned int i = nodes[c];
          double             f[dim] = {}, memory[dim] = {};
          for (unsigned int q = start[c]; q < start[c + 1]; ++q)
            {
              const unsigned int j = col[q];
              double             x = 0.;
              if (nc == 1)
                x = u[0][j] - u[0][i];
              else
                for (unsigned int d = 0; d < dim; ++d)
                  x += direction[dim * q + d] * (u[d][j] - u[d][i]);
              if (update)
                bond_memory[q] = bond_decay[q] * bond_memory[q] + (1. - bond_decay[q]) * x;
              const double fq = weight[q] * (x - bond_memory[q]), mq = weight[q] * bond_memory[q];
              if (nc == 1)
                {
                  f[0] += fq;
                  memory[0] += mq;
                }
              else
                for (unsigned int d = 0; d < dim; ++d)
                  {
                    f[d] += fq * direction[dim * q + d];
                    memory[d] += mq * direction[dim * q + d];
                  }
            }
          for (unsigned int d = 0; d < nc; ++d)
            {
              double &n = node_memory[nc * c + d];
              if (update)
                n = node_decay[c] * n + (1. - node_decay[c]) * f[d];
              force[d][i] -= memory[d] + n;
            }
        }
    }

#define PERIDEAL_INSTANTIATE(dim)                                                              \
  template void find_absorbing_layer<dim>(const Discretization<dim> &, const Domain<dim> &,    \
                                          double, double, std::vector<unsigned int> &,         \
                                          std::vector<Tensor<1, dim>> &);                      \
  template std::vector<double> sponge_profile<dim>(                                            \
    const Discretization<dim> &, const Domain<dim> &, double, double, double, double, double,  \
    const std::function<bool(const Point<dim> &, const Tensor<1, dim> &)> &);                \
  template class PmlBand<dim>;
    PERIDEAL_INSTANTIATE(1)
    PERIDEAL_INSTANTIATE(2)
    PERIDEAL_INSTANTIATE(3)
#undef PERIDEAL_INSTANTIATE
  } // namespace Abc
} // namespace PeriDEAL
