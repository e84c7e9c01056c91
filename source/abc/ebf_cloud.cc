#include <perideal/abc/ebf_cloud.h>
#include <perideal/base/exceptions.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>

namespace PeriDEAL
{
  namespace Abc
  {
    template <int dim>
    EbfCloudBuilder<dim>::EbfCloudBuilder(const std::vector<Point<dim>>              &points,
                                          const std::vector<types::global_dof_index> &ids,
                                          const double                                radius,
                                          const double                                cone_angle,
                                          const double                                dx)
      : points(points)
      , ids(ids)
      , radius(radius)
      , cone_slope(1. / std::tan(std::max(cone_angle, 1e-12)))
      , dx(dx)
      // Bins slightly wider than the radius, so that points at that distance
      // up to round-off are in the neighbouring bins.
      , bin_width(radius * (1. + 1e-6))
    {
      for (unsigned int i = 0; i < points.size(); ++i)
        bins[bin_of(points[i])].push_back(i);
    }

    template <int dim>
    std::array<long, dim>
    EbfCloudBuilder<dim>::bin_of(const Point<dim> &p) const
    {
      std::array<long, dim> b;
      for (unsigned int d = 0; d < dim; ++d)
        b[d] = static_cast<long>(std::floor(p[d] / bin_width));
      return b;
    }

    template <int dim>
    std::vector<typename EbfCloudBuilder<dim>::Entry>
    EbfCloudBuilder<dim>::cone(const unsigned int i, const Tensor<2, dim> &R) const
    {
      const Point<dim>  &xi = points[i];
      std::vector<Entry> out;
      out.emplace_back(i, Tensor<1, dim>());
      const auto   b0 = bin_of(xi);
      unsigned int n_neighbour_bins = 1;
      for (unsigned int d = 0; d < dim; ++d)
        n_neighbour_bins *= 3;
      for (unsigned int nb = 0; nb < n_neighbour_bins; ++nb)
        {
          auto         b = b0;
          unsigned int c = nb;
          for (unsigned int d = 0; d < dim; ++d, c /= 3)
            b[d] += long(c % 3) - 1;
          const auto it = bins.find(b);
          if (it == bins.end())
            continue;
          for (const unsigned int j : it->second)
            {
              if (j == i || xi.distance(points[j]) > radius * (1. + 1e-10))
                continue;
              const Tensor<1, dim> xbar = R * (points[j] - xi);
              double               lat2 = 0.;
              for (unsigned int d = 1; d < dim; ++d)
                lat2 += xbar[d] * xbar[d];
              // (4.86): behind the node and inside the cone.
              if (xbar[0] < -1e-10 * dx && std::sqrt(lat2) < cone_slope * (-xbar[0]) * (1. - 1e-10))
                out.emplace_back(j, xbar);
            }
        }
      std::sort(out.begin() + 1, out.end(),
                [this](const Entry &p, const Entry &q) { return ids[p.first] < ids[q.first]; });
      return out;
    }

    template <int dim>
    std::vector<typename EbfCloudBuilder<dim>::Entry>
    EbfCloudBuilder<dim>::thin(const std::vector<Entry> &cone, const unsigned int stride) const
    {
      static_assert(dim <= 2, "auxiliary grid in 1D and 2D");
      if (stride <= 1)
        return cone;
      std::vector<Entry>     cloud(1, cone[0]);
      std::set<unsigned int> taken{0};
      const double           hs = stride * dx;
      const int              na = int(std::floor(radius / hs + 1e-9));
      for (int ax = 1; ax <= na; ++ax)
        for (int ay = (dim == 2 ? -na : 0); ay <= (dim == 2 ? na : 0); ++ay)
          {
            Tensor<1, dim> g;
            g[0] = -ax * hs;
            if (dim == 2)
              g[dim - 1] = ay * hs;
            if (g.norm() > radius * (1. + 1e-10) ||
                (dim == 2 && std::abs(g[dim - 1]) >= cone_slope * ax * hs))
              continue;
            unsigned int best = 0;
            double       dist = std::numeric_limits<double>::max();
            for (unsigned int c = 1; c < cone.size(); ++c)
              {
                const double dd = (cone[c].second - g).norm();
                if (dd < dist - 1e-12 * dx)
                  {
                    dist = dd;
                    best = c;
                  }
              }
            if (best > 0 && dist < 0.5 * hs && taken.insert(best).second)
              cloud.push_back(cone[best]);
          }
      std::sort(cloud.begin() + 1, cloud.end(),
                [this](const Entry &p, const Entry &q) { return ids[p.first] < ids[q.first]; });
      return cloud;
    }

    template <int dim>
    std::vector<std::pair<unsigned int, Tensor<1, dim>>>
    nearest_cloud_points(const std::vector<std::pair<unsigned int, Tensor<1, dim>>> &cone,
                         const unsigned int                                          n,
                         const std::vector<types::global_dof_index>                 &ids,
                         const double                                                dx,
                         const double                                                search_radius)
    {
      using Entry = std::pair<unsigned int, Tensor<1, dim>>;
      if (cone.size() < n + 1)
        throw ParameterError("Absorbing boundary/Cloud size", std::to_string(n),
                             "1 .. the " + std::to_string(cone.size() - 1) +
                               " cone points within the search radius (Cloud radius) " +
                               std::to_string(search_radius) + " of the boundary DoF with global id " +
                               std::to_string(ids[cone[0].first]) + " (reduce the cloud size or enlarge the cloud radius)");
      // Distance first, then the global id: a rank-independent order.
      std::vector<Entry> rest(cone.begin() + 1, cone.end());
      std::sort(rest.begin(), rest.end(), [&ids](const Entry &p, const Entry &q) {
        const double a = p.second.norm(), b = q.second.norm();
        return a != b ? a < b : ids[p.first] < ids[q.first];
      });
      std::vector<Entry> out(1, cone[0]);
      if (n == 0)
        return out;
      const double dn = rest[n - 1].second.norm();
      for (const auto &e : rest)
        if (e.second.norm() <= dn + 1e-9 * dx)
          out.push_back(e);
      std::sort(out.begin() + 1, out.end(), [&ids](const Entry &p, const Entry &q) { return ids[p.first] < ids[q.first]; });
      return out;
    }

    PseudoInverseFit
    pseudo_inverse_fit(const Eigen::MatrixXcd &M,
                       const Eigen::MatrixXcd &psi,
                       const double            tolerance,
                       const bool              tikhonov)
    {
      PseudoInverseFit                     f;
      const Eigen::BDCSVD<Eigen::MatrixXcd> svd(M, Eigen::ComputeThinU | Eigen::ComputeThinV);
      const auto                          &sv  = svd.singularValues();
      const double                         eps = std::max(M.rows(), M.cols()) * std::numeric_limits<double>::epsilon();
      const double                         tol = tolerance > 0. ? tolerance : eps;
      const double                         cut = tikhonov ? eps : tol;
      Eigen::Index rank = 0;
      while (rank < sv.size() && sv[rank] > cut * sv[0])
        ++rank;
      Eigen::VectorXd inverse = sv.head(rank).cwiseInverse();
      if (tikhonov)
        for (Eigen::Index q = 0; q < rank; ++q)
          inverse[q] = sv[q] / (sv[q] * sv[q] + tol * tol * sv[0] * sv[0]);
      const Eigen::MatrixXcd Vc =
        ((psi * svd.matrixV().leftCols(rank)) * inverse.asDiagonal()) * svd.matrixU().leftCols(rank).adjoint();
      f.V                = Vc.real();
      f.condition_number = rank > 0 ? sv[0] / (tikhonov ? std::max(sv[rank - 1], tol * sv[0]) : sv[rank - 1]) :
                                      std::numeric_limits<double>::infinity();
      f.max_norm         = Vc.cwiseAbs().maxCoeff();
      return f;
    }

    template std::vector<std::pair<unsigned int, Tensor<1, 1>>>
    nearest_cloud_points(const std::vector<std::pair<unsigned int, Tensor<1, 1>>> &, unsigned int,
                         const std::vector<types::global_dof_index> &, double, double);
    template std::vector<std::pair<unsigned int, Tensor<1, 2>>>
    nearest_cloud_points(const std::vector<std::pair<unsigned int, Tensor<1, 2>>> &, unsigned int,
                         const std::vector<types::global_dof_index> &, double, double);
    template std::vector<std::pair<unsigned int, Tensor<1, 3>>>
    nearest_cloud_points(const std::vector<std::pair<unsigned int, Tensor<1, 3>>> &, unsigned int,
                         const std::vector<types::global_dof_index> &, double, double);
    template class EbfCloudBuilder<1>;
    template class EbfCloudBuilder<2>;
  } // namespace Abc
} // namespace PeriDEAL
