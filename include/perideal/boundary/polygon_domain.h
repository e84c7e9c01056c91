#ifndef perideal_boundary_polygon_domain_h
#define perideal_boundary_polygon_domain_h

#include <perideal/discretization/domain.h>

#include <vector>

namespace PeriDEAL
{
  namespace Boundary
  {
    /**
     * A simple polygon (vertices in order, either orientation) with its exact
     * signed distance: the distance to the closest edge, negative inside
     * (even-odd rule). Squares with corners, L-shapes and the Motz rectangle
     * of the fictitious-node studies.
     */
    class PolygonDomain : public Domain<2>
    {
    public:
      /** At least three vertices; throws ParameterError otherwise. */
      explicit PolygonDomain(const std::vector<Point<2>> &vertices);

      bool
      inside(const Point<2> &p) const override;
      BoundingBox<2>
      bounding_box() const override;
      bool
      has_signed_distance() const override
      {
        return true;
      }
      double
      signed_distance(const Point<2> &p) const override;

    private:
      std::vector<Point<2>> vertices;
    };
  } // namespace Boundary
} // namespace PeriDEAL

#endif
