#ifndef perideal_models_stretch_budget_h
#define perideal_models_stretch_budget_h

#include <deal.II/base/point.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace PeriDEAL
{
  /**
   * An amortized, conservative bound on how much the length of any bond of
   * a node can have grown since the node's last exact check, so that a
   * per-step test "some bond length |y_ij| = |xi_ij + u_j - u_i| reached its
   * threshold" (e.g. the switching criterion (3.80) of the adaptive hybrid
   * configuration, or breaking (2.34)) can skip the nodes for which it
   * provably cannot fire, without changing its outcome.
   *
   * Usage: call advance() with every displacement at which the test runs
   * (in order). When node i is checked exactly, call record(i, slack) with
   * a slack such that no bond of i can reach its threshold while its length
   * grows by less than the slack (e.g. min_b (T_b - |y_b|) over the intact
   * bonds b of i with thresholds T_b, or (1 - sqrt(max_b |y_b|^2 / T_b^2))
   * min_b T_b). Afterwards needs_check(i) is false as long as growth(i),
   * the bound below, is smaller than the slack: then no bond of i can have
   * reached its threshold, and the exact test would have found nothing at i.
   *
   * The bound. Nodes are sorted into blocks (a Cartesian grid of cells of
   * side h >= the reach, the longest bond), so every neighbour j of a node i
   * lies in the 3^dim blocks around the block of i. For one step
   * u^n -> u^{n+1} with increments d_k = u_k^{n+1} - u_k^n let [lo_B, hi_B]
   * be the bounding box of the increments of the nodes in those 3^dim
   * blocks. Both d_i and d_j lie in it, so, by the triangle inequality,
   *   |y_ij^{n+1}| - |y_ij^n| <= |d_j - d_i| <= max_{v in [lo_B, hi_B]} |v - d_i|
   *                            = sqrt(sum_c max(d_ic - lo_Bc, hi_Bc - d_ic)^2),
   * the distance from d_i to the farthest corner of the box. growth(i) sums
   * this over the steps since record(i): an upper bound of
   * |y_ij(now)| - |y_ij(record)| for every neighbour j (a path-length bound;
   * it vanishes for rigid translations, unlike the sum of the end points'
   * path lengths |d_i| + |d_j|, which is larger or equal up to a factor
   * sqrt(dim)). Cost per step: O(1) per local node and per block, against
   * O(family size) per node for the exact test.
   *
   * Round-off: the increments, boxes and sums are rounded (relative error
   * about 1e-16 per operation, i.e. absolute errors of order 1e-16 times
   * the largest coordinate or displacement per step); the caller subtracts
   * a safety margin larger than that from the slack (the hybrid model
   * uses 1e-9 of the smallest threshold plus 1e-13 of the lattice extent).
   *
   * The displacement arrays passed to advance() hold one value per local
   * node (owned nodes first, then ghosts) per component, as
   * Vector::begin() of deal.II's distributed vectors with up-to-date ghost
   * values. Only the first n_tracked nodes (the owned ones) have records;
   * all local nodes contribute to the boxes, so the bound is exact per rank
   * and the decisions do not depend on the partition.
   */
  template <int dim>
  class StretchBudget
  {
  public:
    /**
     * Sort the local nodes at @p position into blocks of side
     * @p reach (1 + 1e-9), where @p reach >= the longest bond, and drop all
     * records. The first @p n_tracked nodes can have records.
     */
    void
    reinit(const std::vector<dealii::Point<dim>> &position,
           const unsigned int                     n_tracked,
           const double                           reach)
    {
      const std::size_t n = position.size();
      n_track             = n_tracked;
      dealii::Point<dim> lower;
      for (unsigned int d = 0; d < dim; ++d)
        lower[d] = std::numeric_limits<double>::max();
      for (const auto &x : position)
        for (unsigned int d = 0; d < dim; ++d)
          lower[d] = std::min(lower[d], x[d]);
      const double h = reach * (1. + 1e-9);
      std::array<long, dim> count;
      count.fill(1);
      for (const auto &x : position)
        for (unsigned int d = 0; d < dim; ++d)
          count[d] = std::max(count[d], long(std::floor((x[d] - lower[d]) / h)) + 1);
      n_block = 1;
      for (unsigned int d = 0; d < dim; ++d)
        {
          stride[d] = n_block;
          n_block *= count[d];
        }
      extent = count;
      block.resize(n);
      for (std::size_t k = 0; k < n; ++k)
        {
          std::size_t b = 0;
          for (unsigned int d = 0; d < dim; ++d)
            b += stride[d] * std::size_t(std::floor((position[k][d] - lower[d]) / h));
          block[k] = std::uint32_t(b);
        }
      box.assign(2 * dim * n_block, 0.);
      dilated.assign(2 * dim * n_block, 0.);
      previous.assign(dim * n, 0.);
      increment.assign(dim * std::size_t(n_track), 0.);
      have_previous = false;
      grown.assign(n_track, 0.);
      slack.assign(n_track, -1.);
    }

    /**
     * The displacement @p u (dim arrays, one value per local node) at which
     * the next test runs: add the step from the previous call's displacement
     * to growth() of every node with a record. The first call after reinit()
     * only stores @p u.
     */
    void
    advance(const std::array<const double *, dim> &u)
    {
      const std::size_t n = block.size();
      if (!have_previous)
        {
          for (std::size_t k = 0; k < n; ++k)
            for (unsigned int d = 0; d < dim; ++d)
              previous[dim * k + d] = u[d][k];
          have_previous = true;
          return;
        }
      // Bounding box of the increments per block: [lo_0, hi_0, lo_1, ...].
      for (std::size_t b = 0; b < n_block; ++b)
        for (unsigned int d = 0; d < dim; ++d)
          {
            box[2 * dim * b + 2 * d]     = std::numeric_limits<double>::max();
            box[2 * dim * b + 2 * d + 1] = -std::numeric_limits<double>::max();
          }
      // Nodes come in runs of the same block (lattice order): keep the run's
      // box in registers and merge it into the block's box at the run's end.
      std::array<double, dim> lo, hi;
      std::uint32_t           current = n > 0 ? block[0] : 0;
      const auto              flush   = [&]() {
        double *bx = box.data() + 2 * dim * std::size_t(current);
        for (unsigned int d = 0; d < dim; ++d)
          {
            bx[2 * d]     = std::min(bx[2 * d], lo[d]);
            bx[2 * d + 1] = std::max(bx[2 * d + 1], hi[d]);
          }
      };
      lo.fill(std::numeric_limits<double>::max());
      hi.fill(-std::numeric_limits<double>::max());
      for (std::size_t k = 0; k < n; ++k)
        {
          if (block[k] != current)
            {
              flush();
              current = block[k];
              lo.fill(std::numeric_limits<double>::max());
              hi.fill(-std::numeric_limits<double>::max());
            }
          for (unsigned int d = 0; d < dim; ++d)
            {
              const double inc      = u[d][k] - previous[dim * k + d];
              previous[dim * k + d] = u[d][k];
              lo[d]                 = std::min(lo[d], inc);
              hi[d]                 = std::max(hi[d], inc);
              if (k < n_track)
                increment[dim * k + d] = inc;
            }
        }
      if (n > 0)
        flush();
      // Union over the 3^dim blocks around each block (one direction at a
      // time: separable), empty blocks contribute nothing.
      dilated = box;
      for (unsigned int e = 0; e < dim; ++e)
        {
          scratch = dilated;
          const std::vector<double> &source = scratch;
          for (std::size_t b = 0; b < n_block; ++b)
            {
              const long c = long(b / stride[e]) % extent[e];
              for (const long s : {-1L, 1L})
                {
                  if (c + s < 0 || c + s >= extent[e])
                    continue;
                  const double *nb = source.data() + 2 * dim * (long(b) + s * long(stride[e]));
                  double       *bx = dilated.data() + 2 * dim * b;
                  for (unsigned int d = 0; d < dim; ++d)
                    {
                      bx[2 * d]     = std::min(bx[2 * d], nb[2 * d]);
                      bx[2 * d + 1] = std::max(bx[2 * d + 1], nb[2 * d + 1]);
                    }
                }
            }
        }
      for (unsigned int i = 0; i < n_track; ++i)
        if (slack[i] >= 0.)
          {
            const double *bx = dilated.data() + 2 * dim * std::size_t(block[i]);
            double        s  = 0.;
            for (unsigned int d = 0; d < dim; ++d)
              {
                const double inc = increment[dim * i + d];
                const double far = std::max(inc - bx[2 * d], bx[2 * d + 1] - inc);
                s += far * far;
              }
            grown[i] += std::sqrt(s);
          }
    }

    /**
     * Node @p i (< n_tracked) was checked exactly at the displacement of the
     * last advance(): no bond of i reaches its threshold before its length
     * grows by @p slack_length. A negative slack means "check again at the
     * next test".
     */
    void
    record(const unsigned int i, const double slack_length)
    {
      grown[i] = 0.;
      slack[i] = slack_length >= 0. ? slack_length : -1.;
    }

    /** True if node @p i has no record or growth(i) >= its slack. */
    bool
    needs_check(const unsigned int i) const
    {
      return slack[i] < 0. || grown[i] >= slack[i];
    }

    /** Bound on the growth of the length of every bond of node @p i since its record. */
    double
    growth(const unsigned int i) const
    {
      return grown[i];
    }

    /** Drop all records (e.g. after bonds were restored). */
    void
    invalidate()
    {
      std::fill(slack.begin(), slack.end(), -1.);
    }

    /** Number of blocks. */
    std::size_t
    n_blocks() const
    {
      return n_block;
    }

  private:
    unsigned int                n_track = 0;
    std::size_t                 n_block = 0;
    std::array<std::size_t, dim> stride{};
    std::array<long, dim>        extent{};
    /** Block of each local node. */
    std::vector<std::uint32_t> block;
    /** Per block: increment box, its union over the neighbouring blocks, scratch. */
    std::vector<double> box, dilated, scratch;
    /** Displacement of the last advance() per local node; increments of the tracked nodes. */
    std::vector<double> previous, increment;
    bool                have_previous = false;
    /** Per tracked node: growth bound and slack since its record (< 0: none). */
    std::vector<double> grown, slack;
  };
} // namespace PeriDEAL

#endif
