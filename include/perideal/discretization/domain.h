#ifndef perideal_discretization_domain_h
#define perideal_discretization_domain_h

#include <deal.II/base/bounding_box.h>
#include <deal.II/base/function_parser.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <deal.II/grid/grid_tools_cache.h>
#include <deal.II/grid/tria.h>

#include <memory>
#include <string>

namespace PeriDEAL
{
  using namespace dealii;

  /**
   * The body a PD lattice fills: a point-membership test and a bounding box,
   * plus a signed distance where one is cheap (negative inside). The node
   * generator keeps the lattice points inside the body and, for a volume
   * constraint layer, those outside it within the layer thickness.
   */
  template <int dim>
  class Domain
  {
  public:
    virtual ~Domain() = default;

    /** True if @p p belongs to the (closed) body. */
    virtual bool
    inside(const Point<dim> &p) const = 0;

    /** An axis-aligned box containing the body. */
    virtual BoundingBox<dim>
    bounding_box() const = 0;

    /**
     * True if signed_distance() is available. Without it, layer nodes are
     * found by discrete dilation of the inside set.
     */
    virtual bool
    has_signed_distance() const
    {
      return false;
    }

    /** Signed distance to the boundary, negative inside. */
    virtual double
    signed_distance(const Point<dim> &p) const;

    /** Declare the "Geometry" entries of the parameter file. */
    static void
    declare_parameters(ParameterHandler &prm);

    /**
     * Create the domain described by the current subsection (the caller has
     * entered "Geometry"). Throws ParameterError on bad input, including an
     * unreadable mesh file.
     */
    static std::unique_ptr<Domain<dim>>
    create(ParameterHandler &prm);
  };

  /** The box [lower, upper]. */
  template <int dim>
  class BoxDomain : public Domain<dim>
  {
  public:
    BoxDomain(const Point<dim> &lower, const Point<dim> &upper);
    bool
    inside(const Point<dim> &p) const override;
    BoundingBox<dim>
    bounding_box() const override;
    bool
    has_signed_distance() const override
    {
      return true;
    }
    double
    signed_distance(const Point<dim> &p) const override;

  private:
    Point<dim> lower, upper;
  };

  /** The closed ball of given center and radius. */
  template <int dim>
  class BallDomain : public Domain<dim>
  {
  public:
    BallDomain(const Point<dim> &center, const double radius);
    bool
    inside(const Point<dim> &p) const override;
    BoundingBox<dim>
    bounding_box() const override;
    bool
    has_signed_distance() const override
    {
      return true;
    }
    double
    signed_distance(const Point<dim> &p) const override;

  private:
    Point<dim> center;
    double     radius;
  };

  /**
   * A level-set body {x : f(x) <= 0} inside a given bounding box, with f a
   * muparser expression in x, y, z. If f is a signed distance, the volume
   * constraint layer is exact; the class treats it as one.
   */
  template <int dim>
  class LevelSetDomain : public Domain<dim>
  {
  public:
    LevelSetDomain(const std::string &expression,
                   const Point<dim>  &lower,
                   const Point<dim>  &upper);
    bool
    inside(const Point<dim> &p) const override;
    BoundingBox<dim>
    bounding_box() const override;
    bool
    has_signed_distance() const override
    {
      return true;
    }
    double
    signed_distance(const Point<dim> &p) const override;

  private:
    mutable FunctionParser<dim> function;
    Point<dim>                  lower, upper;
  };

  /**
   * A body given by a deal.II mesh: a GridGenerator shape (by name and
   * argument string, as GridGenerator::generate_from_name_and_arguments) or
   * a gmsh .msh file read with GridIn. Membership is a cell search.
   */
  template <int dim>
  class MeshDomain : public Domain<dim>
  {
  public:
    /** Take a mesh that is already filled. */
    explicit MeshDomain(std::unique_ptr<Triangulation<dim>> tria);
    bool
    inside(const Point<dim> &p) const override;
    BoundingBox<dim>
    bounding_box() const override;

    /** The mesh. */
    const Triangulation<dim> &
    get_triangulation() const
    {
      return *tria;
    }

  private:
    std::unique_ptr<Triangulation<dim>>         tria;
    std::unique_ptr<GridTools::Cache<dim, dim>> cache;
    BoundingBox<dim>                            box;
  };

  /** Parse a point "a, b[, c]" of the right dimension or throw. */
  template <int dim>
  Point<dim>
  parse_point(const std::string &text, const std::string &parameter);
} // namespace PeriDEAL

#endif
