#ifndef perideal_base_exceptions_h
#define perideal_base_exceptions_h

#include <sstream>
#include <stdexcept>
#include <string>

namespace PeriDEAL
{
  /**
   * The error every piece of user input that cannot be honoured ends in: it
   * names the parameter, the value given and what is allowed. The driver
   * and the tutorials catch it (as any std::exception), print the message
   * and return a non-zero exit code; nothing aborts.
   */
  class ParameterError : public std::runtime_error
  {
  public:
    /**
     * @p parameter is the name as it appears in the parameter file
     * (including its subsection path), @p value the offending value and
     * @p allowed a human-readable description of the admissible range.
     */
    ParameterError(const std::string &parameter,
                   const std::string &value,
                   const std::string &allowed)
      : std::runtime_error("Invalid value '" + value + "' for parameter '" +
                           parameter + "': allowed is " + allowed + ".")
      , parameter(parameter)
    {}

    /** The parameter that caused the error. */
    const std::string parameter;
  };

  /**
   * Throw a ParameterError unless @p condition holds. The value is
   * formatted with operator<<.
   */
  template <typename T>
  inline void
  check_parameter(const bool         condition,
                  const std::string &parameter,
                  const T           &value,
                  const std::string &allowed)
  {
    if (!condition)
      {
        std::ostringstream s;
        s.precision(12);
        s << value;
        throw ParameterError(parameter, s.str(), allowed);
      }
  }
} // namespace PeriDEAL

#endif
