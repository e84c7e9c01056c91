#include <deal.II/base/utilities.h>

#include <deal.II/fe/mapping_q1.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_in.h>
#include <deal.II/grid/grid_tools.h>

#include <perideal/base/exceptions.h>
#include <perideal/base/expressions.h>
#include <perideal/discretization/domain.h>

#include <fstream>

namespace PeriDEAL
{
  template <int dim>
  double
  Domain<dim>::signed_distance(const Point<dim> &) const
  {
    throw std::logic_error("This domain has no signed distance.");
  }

  template <int dim>
  Point<dim>
  parse_point(const std::string &text, const std::string &parameter)
  {
    std::vector<double> v;
    try
      {
        v = Utilities::string_to_double(Utilities::split_string_list(text, ','));
      }
    catch (...)
      {
        throw ParameterError(parameter, text,
                             "a comma-separated list of " + std::to_string(dim) +
                               " numbers");
      }
    check_parameter(v.size() == dim, parameter, text,
                    "a comma-separated list of " + std::to_string(dim) + " numbers");
    Point<dim> p;
    for (unsigned int d = 0; d < dim; ++d)
      p[d] = v[d];
    return p;
  }

  template <int dim>
  void
  Domain<dim>::declare_parameters(ParameterHandler &prm)
  {
    prm.declare_entry("Domain", "box",
                      Patterns::Selection("box|ball|level set|mesh"),
                      "The body the PD lattice fills: an axis-aligned box, a ball, "
                      "a level set {f <= 0} or a deal.II mesh (a GridGenerator "
                      "shape or a gmsh .msh file).");
    prm.declare_entry("Lower corner", "-0.5, -0.5, -0.5", Patterns::Anything(),
                      "box/level set: lower corner of the (bounding) box; the first "
                      "'dim' numbers are used.");
    prm.declare_entry("Upper corner", "0.5, 0.5, 0.5", Patterns::Anything(),
                      "box/level set: upper corner of the (bounding) box.");
    prm.declare_entry("Center", "0, 0, 0", Patterns::Anything(), "ball: center.");
    prm.declare_entry("Radius", "1", Patterns::Double(), "ball: radius (> 0).");
    prm.declare_entry("Level set", "x^2 + y^2 - 0.25", Patterns::Anything(),
                      "level set: f(x, y, z) in muparser syntax; the body is "
                      "{f <= 0}. Give a signed distance if a volume constraint "
                      "layer is used: its value is taken as the distance.");
    prm.declare_entry("Grid generator", "hyper_cube", Patterns::Anything(),
                      "mesh: a GridGenerator function name, as accepted by "
                      "GridGenerator::generate_from_name_and_arguments.");
    prm.declare_entry("Grid arguments", "-0.5 : 0.5 : false", Patterns::Anything(),
                      "mesh: the argument string of that GridGenerator function.");
    prm.declare_entry("Mesh file", "", Patterns::Anything(),
                      "mesh: a gmsh .msh file; if not empty it is used instead of "
                      "the grid generator. Relative paths are taken from the "
                      "working directory.");
  }

  namespace
  {
    template <int dim>
    Point<dim>
    first_dim(const std::string &text, const std::string &parameter)
    {
      // Accept longer lists so one parameter file serves several dimensions.
      std::vector<std::string> parts = Utilities::split_string_list(text, ',');
      check_parameter(parts.size() >= dim, parameter, text,
                      "a comma-separated list of at least " +
                        std::to_string(dim) + " numbers");
      parts.resize(dim);
      std::string joined;
      for (unsigned int d = 0; d < dim; ++d)
        joined += (d ? "," : "") + parts[d];
      return parse_point<dim>(joined, parameter);
    }
  } // namespace

  template <int dim>
  std::unique_ptr<Domain<dim>>
  Domain<dim>::create(ParameterHandler &prm)
  {
    const std::string type = prm.get("Domain");
    if (type == "box" || type == "level set")
      {
        const Point<dim> lo = first_dim<dim>(prm.get("Lower corner"), "Geometry/Lower corner");
        const Point<dim> hi = first_dim<dim>(prm.get("Upper corner"), "Geometry/Upper corner");
        for (unsigned int d = 0; d < dim; ++d)
          check_parameter(hi[d] > lo[d], "Geometry/Upper corner", prm.get("Upper corner"),
                          "a point larger than 'Lower corner' in every coordinate");
        if (type == "box")
          return std::make_unique<BoxDomain<dim>>(lo, hi);
        return std::make_unique<LevelSetDomain<dim>>(prm.get("Level set"), lo, hi);
      }
    if (type == "ball")
      {
        const double r = prm.get_double("Radius");
        check_parameter(r > 0., "Geometry/Radius", r, "a positive number");
        return std::make_unique<BallDomain<dim>>(
          first_dim<dim>(prm.get("Center"), "Geometry/Center"), r);
      }
    // mesh
    auto              tria = std::make_unique<Triangulation<dim>>();
    const std::string file = prm.get("Mesh file");
    if (!file.empty())
      {
        std::ifstream in(file);
        if (!in)
          throw ParameterError("Geometry/Mesh file", file, "a readable gmsh .msh file");
        try
          {
            GridIn<dim> grid_in(*tria);
            grid_in.read_msh(in);
          }
        catch (std::exception &e)
          {
            // Keep the reader's own explanation, without deal.II's banner.
            std::string why = e.what();
            const auto  at  = why.find("Additional information:");
            why = at == std::string::npos ? "" : why.substr(at + 23, 200);
            for (char &c : why)
              if (c == '\n')
                c = ' ';
            throw ParameterError("Geometry/Mesh file", file,
                                 "a well-formed gmsh .msh file of dimension " +
                                   std::to_string(dim) +
                                   (why.empty() ? "" : " (reader: " + why + ")"));
          }
      }
    else
      {
        try
          {
            GridGenerator::generate_from_name_and_arguments(*tria,
                                                            prm.get("Grid generator"),
                                                            prm.get("Grid arguments"));
          }
        catch (std::exception &e)
          {
            throw ParameterError("Geometry/Grid generator",
                                 prm.get("Grid generator") + "(" + prm.get("Grid arguments") + ")",
                                 "a GridGenerator function of dimension " +
                                   std::to_string(dim) + " with matching arguments");
          }
      }
    check_parameter(tria->n_active_cells() > 0, "Geometry/Mesh file", file,
                    "a mesh with at least one cell");
    return std::make_unique<MeshDomain<dim>>(std::move(tria));
  }

  // ---------------------------------------------------------------- Box
  template <int dim>
  BoxDomain<dim>::BoxDomain(const Point<dim> &lower, const Point<dim> &upper)
    : lower(lower)
    , upper(upper)
  {}

  template <int dim>
  bool
  BoxDomain<dim>::inside(const Point<dim> &p) const
  {
    // Lattice points on a face come out of origin + i dx with round-off of
    // either sign (the origin moves with the layer thickness); they belong
    // to the body.
    return signed_distance(p) <= 1e-12 * lower.distance(upper);
  }

  template <int dim>
  BoundingBox<dim>
  BoxDomain<dim>::bounding_box() const
  {
    return BoundingBox<dim>(std::make_pair(lower, upper));
  }

  template <int dim>
  double
  BoxDomain<dim>::signed_distance(const Point<dim> &p) const
  {
    // Exact Euclidean signed distance of a box.
    double outside2 = 0., inside_max = -1e300;
    for (unsigned int d = 0; d < dim; ++d)
      {
        const double q = std::max(lower[d] - p[d], p[d] - upper[d]);
        if (q > 0)
          outside2 += q * q;
        inside_max = std::max(inside_max, q);
      }
    return outside2 > 0 ? std::sqrt(outside2) : inside_max;
  }

  // ---------------------------------------------------------------- Ball
  template <int dim>
  BallDomain<dim>::BallDomain(const Point<dim> &center, const double radius)
    : center(center)
    , radius(radius)
  {}

  template <int dim>
  bool
  BallDomain<dim>::inside(const Point<dim> &p) const
  {
    return p.distance(center) <= radius;
  }

  template <int dim>
  BoundingBox<dim>
  BallDomain<dim>::bounding_box() const
  {
    Point<dim> lo = center, hi = center;
    for (unsigned int d = 0; d < dim; ++d)
      {
        lo[d] -= radius;
        hi[d] += radius;
      }
    return BoundingBox<dim>(std::make_pair(lo, hi));
  }

  template <int dim>
  double
  BallDomain<dim>::signed_distance(const Point<dim> &p) const
  {
    return p.distance(center) - radius;
  }

  // ---------------------------------------------------------------- Level set
  template <int dim>
  LevelSetDomain<dim>::LevelSetDomain(const std::string &expression,
                                      const Point<dim>  &lower,
                                      const Point<dim>  &upper)
    : lower(lower)
    , upper(upper)
  {
    try
      {
        function.initialize(FunctionParser<dim>::default_variable_names(),
                            expression,
                            expression_constants(dim));
      }
    catch (...)
      {
        throw ParameterError("Geometry/Level set", expression,
                             "a muparser expression in the coordinates x, y, z");
      }
  }

  template <int dim>
  bool
  LevelSetDomain<dim>::inside(const Point<dim> &p) const
  {
    for (unsigned int d = 0; d < dim; ++d)
      if (p[d] < lower[d] || p[d] > upper[d])
        return false;
    return function.value(p) <= 0.;
  }

  template <int dim>
  BoundingBox<dim>
  LevelSetDomain<dim>::bounding_box() const
  {
    return BoundingBox<dim>(std::make_pair(lower, upper));
  }

  template <int dim>
  double
  LevelSetDomain<dim>::signed_distance(const Point<dim> &p) const
  {
    return function.value(p);
  }

  // ---------------------------------------------------------------- Mesh
  template <int dim>
  MeshDomain<dim>::MeshDomain(std::unique_ptr<Triangulation<dim>> t)
    : tria(std::move(t))
    , cache(std::make_unique<GridTools::Cache<dim, dim>>(*tria))
    , box(GridTools::compute_bounding_box(*tria))
  {}

  template <int dim>
  bool
  MeshDomain<dim>::inside(const Point<dim> &p) const
  {
    if (!box.point_inside(p, 1e-12))
      return false;
    try
      {
        const auto cell_and_ref =
          GridTools::find_active_cell_around_point(*cache, p);
        return cell_and_ref.first.state() == IteratorState::valid;
      }
    catch (...)
      {
        return false;
      }
  }

  template <int dim>
  BoundingBox<dim>
  MeshDomain<dim>::bounding_box() const
  {
    return box;
  }

#define PERIDEAL_INSTANTIATE(dim)                                              \
  template class Domain<dim>;                                                  \
  template class BoxDomain<dim>;                                               \
  template class BallDomain<dim>;                                              \
  template class LevelSetDomain<dim>;                                          \
  template class MeshDomain<dim>;                                              \
  template Point<dim> parse_point<dim>(const std::string &, const std::string &);
  PERIDEAL_INSTANTIATE(1)
  PERIDEAL_INSTANTIATE(2)
  PERIDEAL_INSTANTIATE(3)
#undef PERIDEAL_INSTANTIATE
} // namespace PeriDEAL
