#ifndef perideal_base_expressions_h
#define perideal_base_expressions_h

#include <cmath>
#include <map>
#include <string>

namespace PeriDEAL
{
  /**
   * The constants every muparser expression of a parameter file may use:
   * pi, and the coordinates a @p dim-dimensional run does not have (y, z),
   * set to 0, so that one expression serves 1D, 2D and 3D runs.
   */
  inline std::map<std::string, double>
  expression_constants(const unsigned int dim)
  {
    std::map<std::string, double> c{{"pi", M_PI}};
    if (dim < 3)
      c["z"] = 0.;
    if (dim < 2)
      c["y"] = 0.;
    return c;
  }
} // namespace PeriDEAL

#endif
