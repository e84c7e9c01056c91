#include <perideal/io/plot.h>

#include <cstdlib>
#include <fstream>
#include <iostream>

namespace PeriDEAL
{
  bool
  run_gnuplot(const std::string &script_file, const std::string &script, const std::string &image)
  {
    if (std::system("command -v gnuplot > /dev/null 2>&1") != 0)
      {
        std::cout << "(gnuplot not found: " << image << " not written)" << std::endl;
        return false;
      }
    std::ofstream(script_file) << script;
    if (std::system(("gnuplot '" + script_file + "' 2> /dev/null").c_str()) != 0)
      {
        std::cout << "(gnuplot failed on " << script_file << ")" << std::endl;
        return false;
      }
    std::cout << "Plot: " << image << std::endl;
    return true;
  }

  std::string
  gnuplot_png_preamble(const std::string &image)
  {
    return "set terminal pngcairo size 900,600 noenhanced\nset output '" + image +
           "'\nset grid\n";
  }
} // namespace PeriDEAL
