#ifndef perideal_io_plot_h
#define perideal_io_plot_h

#include <string>

namespace PeriDEAL
{
  /**
   * Write a gnuplot @p script to @p script_file and run it, if gnuplot is
   * installed. Plots are a convenience: without gnuplot (or if it fails) the
   * function says so on stdout and returns false, it never throws. Call it on
   * one rank only.
   *
   * The script should set its own terminal and output file; @p image names
   * that file for the message printed on success.
   */
  bool
  run_gnuplot(const std::string &script_file,
              const std::string &script,
              const std::string &image);

  /** The usual preamble: a 900x600 PNG terminal writing @p image. */
  std::string
  gnuplot_png_preamble(const std::string &image);
} // namespace PeriDEAL

#endif
