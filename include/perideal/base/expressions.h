#ifndef perideal_base_expressions_h
#define perideal_base_expressions_h

#include <deal.II/base/function_parser.h>
#include <deal.II/base/utilities.h>

#include <perideal/base/exceptions.h>

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

  /**
   * Initializes @p f with a muparser expression in x, y, z, t, the
   * expression_constants() and the user's @p constants ("a=1, b=2"); bad
   * input throws a ParameterError naming @p parameter (the expression) or
   * @p constants_parameter (the constants).
   */
  template <int dim>
  void
  init_expression(dealii::FunctionParser<dim> &f,
                  const std::string           &expression,
                  const std::string           &constants,
                  const std::string           &parameter,
                  const std::string           &constants_parameter)
  {
    std::map<std::string, double> c = expression_constants(dim);
    for (const auto &entry : dealii::Utilities::split_string_list(constants, ','))
      {
        const auto kv = dealii::Utilities::split_string_list(entry, '=');
        check_parameter(kv.size() == 2, constants_parameter, constants, "a list 'name=value, ...'");
        c[kv[0]] = dealii::Utilities::string_to_double(kv[1]);
      }
    try
      {
        f.initialize(dealii::FunctionParser<dim>::default_variable_names() + ",t", expression, c, true);
        // Evaluate once so that syntax errors surface here, named.
        f.value(dealii::Point<dim>());
      }
    catch (std::exception &)
      {
        throw ParameterError(parameter, expression,
                             "a muparser expression in x, y, z, t and the constants");
      }
  }
} // namespace PeriDEAL

#endif
