#ifndef perideal_io_node_output_h
#define perideal_io_node_output_h

#include <perideal/discretization/discretization.h>

#include <string>
#include <utility>
#include <vector>

namespace PeriDEAL
{
  using namespace dealii;

  /**
   * ParaView output of the nodes as a point cloud.
   *
   * Every call of write() produces one snapshot: a
   * <tt>directory/basename_NNNNN.pvtu</tt> record plus one
   * <tt>basename_NNNNN.R.vtu</tt> piece per MPI rank (R as chosen by
   * DataOutInterface::write_vtu_with_pvtu_record()), NNNNN being a running
   * snapshot counter. Each piece has one vertex per owned node with the
   * given scalar fields and, automatically, the point data 'rank', 'region'
   * and 'node_id'. Afterwards rank 0 rewrites <tt>directory/basename.pvd</tt>,
   * the time series of all snapshots so far, atomically (temporary file plus
   * rename), so ParaView never sees a half-written series.
   *
   * @note Point data are stored as 32-bit floats (the format of
   * DataOutBase::Patch), so 'node_id' is exact only below 2^24 nodes.
   */
  template <int dim>
  class NodeOutput
  {
  public:
    /**
     * Prepare output of the nodes of @p discretization into @p directory,
     * which rank 0 creates if needed. Collective. The discretization must
     * outlive this object; write() uses its current positions.
     */
    NodeOutput(const Discretization<dim> &discretization,
               const std::string         &directory,
               const std::string         &basename = "solution");

    /**
     * Write a snapshot of the owned nodes with the scalar node @p fields
     * (name and vector on Discretization::partitioner(); only owned entries
     * are read, ghosts need not be up to date). @p time goes into the pvd
     * series, @p time and @p step into the VTU field data (TIME, CYCLE).
     * Collective. Returns the name of the pvtu record (without directory).
     * Throws std::invalid_argument for an empty or reserved field name or a
     * vector of the wrong layout.
     */
    std::string
    write(const double                                                  time,
          const unsigned int                                            step,
          const std::vector<std::pair<std::string, const Vector *>> &fields);

    /**
     * Continue the series of an earlier run that is restarted at @p time:
     * rank 0 reads the existing pvd file (if any), keeps the snapshots with
     * time <= @p time (up to a relative 1e-10, as DataOutBase::write_pvd_record()
     * rounds times to 12 digits), rewrites the pvd
     * file with them, and the next snapshot gets the number following the
     * last one kept, so later snapshots of the old run are overwritten.
     * Without a pvd file the series starts afresh at 0. Collective.
     */
    void
    restart(const double time);

    /**
     * Set the series explicitly: @p records are the (time, pvtu name) pairs
     * that the pvd file lists and @p next_counter is the number of the next
     * snapshot. Rank 0 rewrites the pvd file. Collective; use restart()
     * unless the series is kept elsewhere.
     */
    void
    set_records(const unsigned int                                 next_counter,
                const std::vector<std::pair<double, std::string>> &records);

    /** Number the next snapshot will get. */
    unsigned int
    get_counter() const
    {
      return counter;
    }

    /** The (time, pvtu name) pairs of the series so far. */
    const std::vector<std::pair<double, std::string>> &
    get_records() const
    {
      return records;
    }

    /** Path of the pvd file. */
    std::string
    pvd_filename() const;

  private:
    /** Rank 0 writes the pvd file atomically; errors are thrown on all ranks. */
    void
    write_pvd() const;

    const Discretization<dim>                   &discretization;
    const std::string                            directory;
    const std::string                            basename;
    unsigned int                                 counter = 0;
    std::vector<std::pair<double, std::string>> records;
  };
} // namespace PeriDEAL

#endif
