#ifndef perideal_multigrid_lattice_tools_h
#define perideal_multigrid_lattice_tools_h

#include <deal.II/base/point.h>

#include <perideal/discretization/discretization.h>
#include <perideal/multigrid/multigrid_discretization.h>

#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace PeriDEAL
{
  namespace MultiGrid
  {
    /**
     * Integer-lattice helpers shared by the serial multi-grid
     * (MultiGrid::Discretization) and the octree multi-grid
     * (MultiGrid::OctreeMultiGrid): lattice stencils, linear indices and the
     * interpolation of a point from the corners of its enclosing lattice
     * cell, (3.85)-(3.88). One implementation, so both give the same numbers.
     */
    namespace Lattice
    {
      template <int dim>
      using Index = std::array<long long, dim>;

      // Offsets o != 0 of the lattice stencil with beta(|o| h) > 0.
      template <int dim>
      std::vector<std::pair<Index<dim>, double>>
      stencil(const double h, const double delta, const bool partial_volume)
      {
        const long long reach = (long long)std::ceil((delta + 0.5 * h) / h) + 1;
        std::vector<std::pair<Index<dim>, double>> out;
        Index<dim>                                 o;
        const long long                            n = 2 * reach + 1;
        long long                                  total = 1;
        for (unsigned int d = 0; d < dim; ++d)
          total *= n;
        for (long long k = 0; k < total; ++k)
          {
            long long rest = k;
            double    r2   = 0.;
            bool      zero = true;
            for (unsigned int d = 0; d < dim; ++d)
              {
                o[d] = rest % n - reach;
                rest /= n;
                r2 += double(o[d] * o[d]) * h * h;
                zero = zero && o[d] == 0;
              }
            if (zero)
              continue;
            const double r    = std::sqrt(r2);
            const double beta = PeriDEAL::Discretization<dim>::volume_factor(r, delta, h,
                                                                             partial_volume);
            if (beta > 0.)
              out.emplace_back(o, r);
          }
        return out;
      }

      template <int dim>
      long long
      linear(const Index<dim> &i, const Index<dim> &n)
      {
        long long k = 0;
        for (int d = dim - 1; d >= 0; --d)
          k = k * n[d] + i[d];
        return k;
      }

      template <int dim>
      bool
      in_range(const Index<dim> &i, const Index<dim> &n)
      {
        for (unsigned int d = 0; d < dim; ++d)
          if (i[d] < 0 || i[d] >= n[d])
            return false;
        return true;
      }

      // Weights of the 2^dim (deduplicated) corners for a point at local
      // coordinates t in [0,1]^dim of a lattice cell.
      template <int dim>
      void
      corner_weights(const Point<dim>              &x,
                     const std::vector<Point<dim>> &corner,
                     const std::vector<double>     &multilinear,
                     const Interpolation            scheme,
                     const double                   h,
                     std::vector<double>           &w)
      {
        w.assign(corner.size(), 0.);
        if (scheme == Interpolation::multilinear)
          {
            w = multilinear;
            return;
          }
        // (3.85)-(3.88): inverse distance; a coincident node takes all
        for (unsigned int j = 0; j < corner.size(); ++j)
          if (x.distance(corner[j]) < 1e-10 * h)
            {
              std::fill(w.begin(), w.end(), 0.);
              w[j] = 1.;
              return;
            }
        double s = 0.;
        for (unsigned int j = 0; j < corner.size(); ++j)
          s += (w[j] = 1. / x.distance(corner[j]));
        for (double &wj : w)
          wj /= s;
      }

      // Corners of the cell of the lattice {origin + i h} containing x, in
      // [0, n); indices clamped at the lattice end (a point in the last
      // half cell then uses the boundary row only). Returns corner indices
      // (deduplicated) and their d-linear weights.
      template <int dim>
      void
      enclosing_corners(const Point<dim>                  &x,
                        const Point<dim>                  &origin,
                        const double                       h,
                        const Index<dim>                  &n,
                        std::vector<Index<dim>>           &corners,
                        std::vector<double>               &multilinear)
      {
        Index<dim>            base;
        std::array<double, dim> t;
        for (unsigned int d = 0; d < dim; ++d)
          {
            const double s = (x[d] - origin[d]) / h;
            base[d]        = (long long)std::floor(s + 1e-10);
            t[d]           = s - base[d];
            if (std::abs(t[d]) < 1e-10)
              t[d] = 0.;
            if (base[d] < 0)
              base[d] = 0, t[d] = 0.;
            if (base[d] >= n[d] - 1)
              base[d] = n[d] - 1, t[d] = 0.;
          }
        // a coordinate on a lattice plane (t = 0) uses that plane only
        corners.clear();
        multilinear.clear();
        for (unsigned int c = 0; c < (1u << dim); ++c)
          {
            Index<dim> i;
            double     w    = 1.;
            bool       skip = false;
            for (unsigned int d = 0; d < dim; ++d)
              {
                const bool up = (c >> d) & 1u;
                skip          = skip || (up && t[d] == 0.);
                i[d]          = base[d] + (up ? 1 : 0);
                w *= up ? t[d] : 1. - t[d];
              }
            if (skip)
              continue;
            corners.push_back(i);
            multilinear.push_back(w);
          }
      }

      // Index i of the linear index k (d = 0 fastest), the inverse of linear().
      template <int dim>
      Index<dim>
      unravel(long long k, const Index<dim> &n)
      {
        Index<dim> i;
        for (unsigned int d = 0; d < dim; ++d)
          {
            i[d] = k % n[d];
            k /= n[d];
          }
        return i;
      }
    } // namespace Lattice
  } // namespace MultiGrid
} // namespace PeriDEAL

#endif
