#ifndef perideal_tests_check_h
#define perideal_tests_check_h

// Minimal assertion helpers for PeriDEAL tests: a failed check prints what
// was compared and makes the test program return non-zero.

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

namespace PeriDEALTests
{
  inline int &
  failures()
  {
    static int n = 0;
    return n;
  }

  /** Parameters of type P (declare_parameters / parse_parameters) from text. */
  template <typename P>
  P
  parameters_from_text(const std::string &text)
  {
    dealii::ParameterHandler prm;
    P::declare_parameters(prm);
    prm.parse_input_from_string(text);
    P p;
    p.parse_parameters(prm);
    return p;
  }

  inline bool
  root()
  {
    return dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  }

  /** x in scientific notation with 4 significant digits, for check messages. */
  inline std::string
  sci(const double x)
  {
    std::ostringstream s;
    s.precision(3);
    s << std::scientific << x;
    return s.str();
  }

  /** Record a check; print on rank 0. */
  inline void
  check(const bool ok, const std::string &what)
  {
    if (!ok)
      ++failures();
    if (root())
      std::cout << (ok ? "  ok    " : "  FAIL  ") << what << std::endl;
  }

  /** |a - b| <= rtol |b| (+ atol). */
  inline void
  check_close(const double       a,
              const double       b,
              const double       rtol,
              const std::string &what,
              const double       atol = 0.)
  {
    std::ostringstream s;
    s.precision(15);
    s << what << ": " << a << " vs " << b << " (rel. diff "
      << std::abs(a - b) / (std::abs(b) > 0 ? std::abs(b) : 1.) << ", tol " << rtol
      << ")";
    check(std::abs(a - b) <= rtol * std::abs(b) + atol, s.str());
  }

  /**
   * Run the named sub-test given as argv[1] (or all of them without an
   * argument) and return the exit code.
   */
  inline int
  run(int argc, char **argv, const std::map<std::string, std::function<void()>> &tests)
  {
    dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
    try
      {
        for (const auto &t : tests)
          if (argc < 2 || t.first == argv[1])
            {
              if (root())
                std::cout << "[" << t.first << "]" << std::endl;
              t.second();
            }
        if (argc >= 2 && tests.find(argv[1]) == tests.end())
          {
            std::cerr << "unknown test " << argv[1] << std::endl;
            return 2;
          }
      }
    catch (std::exception &e)
      {
        std::cerr << "exception: " << e.what() << std::endl;
        return 3;
      }
    const int total = dealii::Utilities::MPI::max(failures(), MPI_COMM_WORLD);
    if (root())
      std::cout << (total == 0 ? "PASSED" : "FAILED") << std::endl;
    return total == 0 ? 0 : 1;
  }
} // namespace PeriDEALTests

#endif
