#ifndef perideal_io_time_series_h
#define perideal_io_time_series_h

#include <deal.II/base/mpi.h>

#include <string>
#include <vector>

namespace PeriDEAL
{
  using namespace dealii;

  /**
   * A CSV time series (energies, norms, errors over time) written by rank 0.
   *
   * The first line is the comma-separated header, each further line one
   * row printed with 16 significant digits. The rows are kept in memory and
   * the whole file is rewritten atomically (temporary file plus rename) on
   * every change, so that it is always complete and readable while a run is
   * going on or after it crashed. Meant for at most a few thousand rows.
   *
   * The first column is taken as the time by truncate_after(). All methods
   * that change the file are collective: every rank calls them with the same
   * arguments (only rank 0's values are written), and an I/O error is thrown
   * on all ranks rather than on rank 0 alone.
   *
   * The constructor does not touch the file: a restarted run calls
   * load_existing() (or passes @p load_existing_file) and truncate_after()
   * before adding rows; a fresh run overwrites the old file on the first
   * add_row().
   */
  class TimeSeries
  {
  public:
    /**
     * A series with the given column names (non-empty, without comma, quote
     * or line break; else std::invalid_argument) in @p filename, whose
     * directory must exist. With @p load_existing_file, load_existing() is
     * called. Collective in that case.
     */
    TimeSeries(const MPI_Comm                  comm,
               const std::string              &filename,
               const std::vector<std::string> &columns,
               const bool                      load_existing_file = false);

    /**
     * Append a row to the file (a full atomic rewrite if the file is not in step with the rows in memory). Throws std::invalid_argument if
     * @p values does not have one entry per column. Collective.
     */
    void
    add_row(const std::vector<double> &values);

    /**
     * Replace the rows in memory by those of an existing file, for a
     * restarted run. Returns false (and keeps no rows) if the file does not
     * exist; throws std::runtime_error if its header differs from the
     * columns of this object or a row cannot be parsed. The file itself is
     * not changed. Collective.
     */
    bool
    load_existing();

    /**
     * Drop the rows whose first column exceeds @p time (with a relative
     * tolerance of 1e-14 for values read back from 16 digits) and rewrite
     * the file. Used when a run restarts from a checkpoint at @p time.
     * Collective.
     */
    void
    truncate_after(const double time);

    /** Rewrite the file from the rows in memory. Collective. */
    void
    write() const;

    /** The rows (identical on all ranks). */
    const std::vector<std::vector<double>> &
    rows() const
    {
      return data;
    }

    /** The column names. */
    const std::vector<std::string> &
    columns() const
    {
      return column_names;
    }

    /** The file name. */
    const std::string &
    get_filename() const
    {
      return filename;
    }

  private:
    MPI_Comm                         mpi_communicator;
    std::string                      filename;
    std::vector<std::string>         column_names;
    std::vector<std::vector<double>> data;
    /** Rows of data that the file holds (appending continues from there). */
    mutable std::size_t rows_on_disk = 0;
  };
} // namespace PeriDEAL

#endif
