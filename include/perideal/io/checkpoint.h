#ifndef perideal_io_checkpoint_h
#define perideal_io_checkpoint_h

#include <perideal/discretization/discretization.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace PeriDEAL
{
  using namespace dealii;

  /**
   * @name Checkpoints and node tables
   *
   * Both are keyed by the node id (Discretization::id), which does not
   * depend on the number of MPI ranks: a run may be restarted, or its node
   * table compared, on any number of ranks. Writers gather all owned nodes
   * on rank 0 (memory of order n_nodes * (n_fields + 1) there) and write
   * atomically: to <tt>path.tmp</tt>, which is then renamed to @p path, so a
   * crash never leaves a half-written file under the final name. All
   * functions taking a Discretization are collective on its communicator
   * and throw the same exception on all ranks.
   */
  /** @{ */

  /**
   * Write a checkpoint of the owned entries of @p fields (vectors on
   * Discretization::partitioner()) with the time step @p step and @p time.
   * @p signature identifies what the data belong to (e.g. a hash of the
   * discretization part of the parameter file); read_checkpoint() insists on
   * the same one.
   *
   * Binary layout (native byte order, checked on reading):
   * "PERIDEAL-CKPT", uint32 byte order mark 0x01020304, uint32 format
   * version, uint32 dim, uint64 n_nodes, uint32 n_fields, uint64 step,
   * double time, uint64 signature length, signature bytes, then n_nodes
   * records (uint64 id, n_fields doubles) sorted by id, and a uint64
   * checksum of the records.
   *
   * Throws std::invalid_argument for a vector of the wrong layout and
   * std::runtime_error if the file cannot be written.
   */
  template <int dim>
  void
  write_checkpoint(const std::string               &path,
                   const Discretization<dim>       &discretization,
                   const unsigned int               step,
                   const double                     time,
                   const std::vector<const Vector *> &fields,
                   const std::string               &signature);

  /**
   * Read a checkpoint written by write_checkpoint(), possibly on another
   * number of ranks, into the owned entries of @p fields (ghost values are
   * not updated: call update_ghost_values() afterwards). Returns false, and
   * changes nothing, if @p path does not exist.
   *
   * Rank 0 reads the file in blocks and broadcasts them; each rank picks its
   * owned ids by binary search. Throws std::runtime_error with a message
   * naming the file if it is malformed, truncated or corrupted (checksum),
   * or written for another dim, node count, field count or signature, or
   * if an owned node id is missing from it. Header errors leave the fields
   * untouched; errors found in the records (checksum, missing id) are
   * detected only after the fields were overwritten, which then hold
   * undefined values.
   */
  template <int dim>
  bool
  read_checkpoint(const std::string         &path,
                  const Discretization<dim> &discretization,
                  unsigned int              &step,
                  double                    &time,
                  const std::vector<Vector *> &fields,
                  const std::string         &signature);

  /**
   * Write a CSV table of all nodes sorted by id, with the columns id, x[, y[,
   * z]] and one per field (names without comma, quote or line break), in 17
   * significant digits, i.e. exactly. For users and to compare runs on
   * different numbers of ranks with compare_node_tables().
   */
  template <int dim>
  void
  write_node_table(const std::string &path,
                   const Discretization<dim> &discretization,
                   const std::vector<std::pair<std::string, const Vector *>> &fields);

  /**
   * The largest absolute difference between the field columns (not id or
   * coordinates) of two tables written by write_node_table(); infinity if a
   * value is NaN in one table only. Throws std::runtime_error if a file
   * cannot be read or parsed, or if the headers or the ids differ. Not
   * collective: any process may call it.
   */
  double
  compare_node_tables(const std::string &a, const std::string &b);

  /** @} */

  /**
   * Replace @p filename by @p contents atomically: write
   * <tt>filename.tmp</tt>, flush it to disk and rename it. Throws
   * std::runtime_error on failure (the old file is then untouched). Not
   * collective.
   */
  void
  write_file_atomically(const std::string &filename, const std::string &contents);

  namespace internal
  {
    /**
     * Run @p f on rank 0 of @p comm only and throw what it throws (as
     * std::runtime_error with the same message) on all ranks, so that an
     * I/O error on rank 0 cannot leave the other ranks waiting in the next
     * collective call. Collective; also orders everything rank 0 does in
     * @p f before whatever the other ranks do after the call.
     */
    void
    run_on_root(const MPI_Comm comm, const std::function<void()> &f);
  } // namespace internal
} // namespace PeriDEAL

#endif
