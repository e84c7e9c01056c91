#include <perideal/base/exceptions.h>
#include <perideal/boundary/polygon_domain.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace PeriDEAL
{
  namespace Boundary
  {
    PolygonDomain::PolygonDomain(const std::vector<Point<2>> &vertices)
      : vertices(vertices)
    {
      check_parameter(vertices.size() >= 3, "Polygon vertices", vertices.size(), ">= 3 vertices");
    }

    bool
    PolygonDomain::inside(const Point<2> &p) const
    {
      return signed_distance(p) <= 0.;
    }

    BoundingBox<2>
    PolygonDomain::bounding_box() const
    {
      return BoundingBox<2>(vertices);
    }

    double
    PolygonDomain::signed_distance(const Point<2> &p) const
    {
      double distance = std::numeric_limits<double>::max();
      bool   in       = false;
      for (unsigned int k = 0; k < vertices.size(); ++k)
        {
          const Point<2>    &a = vertices[k];
          const Point<2>    &b = vertices[(k + 1) % vertices.size()];
          const Tensor<1, 2> t = b - a;
          const double       s = std::clamp(((p - a) * t) / (t * t), 0., 1.);
          distance             = std::min(distance, p.distance(a + s * t));
          // Even-odd crossing of the ray to +x.
          if ((a[1] > p[1]) != (b[1] > p[1]) &&
              p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]))
            in = !in;
        }
      return in ? -distance : distance;
    }
  } // namespace Boundary
} // namespace PeriDEAL
