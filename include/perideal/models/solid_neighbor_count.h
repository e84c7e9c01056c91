#ifndef perideal_models_solid_neighbor_count_h
#define perideal_models_solid_neighbor_count_h

#include <cstdint>
#include <vector>

namespace PeriDEAL
{
  /**
   * Per row of a CSR bond table, the number of columns whose node is solid,
   * kept up to date incrementally while the phase field changes: the
   * corrosion operators use it to pick the cheap kernel of a row whose
   * bonds all have the same micro-diffusivity (all neighbours of one phase)
   * and to fall back to the per-bond kernel only on the interface band.
   *
   * The transpose of the table (for each column node the rows that contain
   * it) is stored once, so a phase flip of node j costs the number of rows
   * containing j; no symmetry of the neighbourhoods is assumed. update()
   * compares the current flags with the stored ones (O(columns)), so the
   * counts are exact for any sequence of phase fields, including ones a
   * caller changed behind the solver's back (e.g. read from a checkpoint).
   */
  class SolidNeighborCount
  {
  public:
    /**
     * Rows 0..n_rows-1 with columns col[row_start[r]..row_start[r+1]), column
     * indices in 0..n_columns-1; solid(j) gives the current phase.
     */
    template <typename Offset, typename Index, typename Solid>
    void
    initialize(const unsigned int n_rows,
               const Offset      *row_start,
               const Index       *col,
               const unsigned int n_columns,
               const Solid       &solid)
    {
      flag.assign(n_columns, 0);
      for (unsigned int j = 0; j < n_columns; ++j)
        flag[j] = solid(j) ? 1 : 0;
      count.assign(n_rows, 0);
      size.assign(n_rows, 0);
      t_start.assign(n_columns + 1, 0);
      for (unsigned int r = 0; r < n_rows; ++r)
        {
          size[r] = row_start[r + 1] - row_start[r];
          for (Offset b = row_start[r]; b < row_start[r + 1]; ++b)
            {
              ++t_start[col[b] + 1];
              count[r] += flag[col[b]];
            }
        }
      for (unsigned int j = 0; j < n_columns; ++j)
        t_start[j + 1] += t_start[j];
      t_row.resize(t_start.back());
      std::vector<std::uint64_t> next(t_start.begin(), t_start.end() - 1);
      for (unsigned int r = 0; r < n_rows; ++r)
        for (Offset b = row_start[r]; b < row_start[r + 1]; ++b)
          t_row[next[col[b]]++] = r;
    }

    /** True once initialize() was called. */
    bool
    initialized() const
    {
      return !size.empty() || !flag.empty();
    }

    /** Bring the counts up to date with the phase field solid(j). */
    template <typename Solid>
    void
    update(const Solid &solid)
    {
      for (unsigned int j = 0; j < flag.size(); ++j)
        {
          const unsigned char s = solid(j) ? 1 : 0;
          if (s != flag[j])
            {
              flag[j] = s;
              for (std::uint64_t t = t_start[j]; t < t_start[j + 1]; ++t)
                count[t_row[t]] += s ? 1 : -1;
            }
        }
    }

    /**
     * -1 if row @p r has columns of both phases, otherwise the phase of all
     * its columns (0 liquid, 1 solid; 0 for an empty row).
     */
    int
    uniform_phase(const unsigned int r) const
    {
      return count[r] == 0 ? 0 : (count[r] == size[r] ? 1 : -1);
    }

    /**
     * The phase flags of the last initialize()/update() (1 solid, 0 liquid),
     * one per column node: a byte gather for the per-bond kernels of the
     * mixed rows instead of a comparison of the phase field's doubles.
     */
    const unsigned char *
    solid_flags() const
    {
      return flag.data();
    }

  private:
    std::vector<unsigned char> flag;
    std::vector<unsigned int>  count, size;
    std::vector<std::uint64_t> t_start;
    std::vector<unsigned int>  t_row;
  };

  namespace internal
  {
    /**
     * sum_k w[k] kappa(col[k]) (c[col[k]] - c_i) over one CSR row of @p m
     * bonds in four independent chains (one chain is latency-bound): the
     * corrosion rows with one kappa per row (neighbours of one phase) or
     * one per bond from the neighbour's phase flag (interface band).
     */
    template <typename Index, typename Kappa>
#if defined(__GNUC__) && !defined(__clang__)
    // scalar loads: AVX-512 gathers cost more than they save on such rows
    __attribute__((optimize("no-tree-vectorize")))
#endif
    inline double
    phase_row_sum(const Index       *col,
                  const double      *w,
                  const unsigned int m,
                  const double      *c,
                  const double       c_i,
                  const Kappa       &kappa)
    {
      double       s0 = 0., s1 = 0., s2 = 0., s3 = 0.;
      unsigned int k  = 0;
      for (; k + 4 <= m; k += 4)
        {
          s0 += w[k] * kappa(col[k]) * (c[col[k]] - c_i);
          s1 += w[k + 1] * kappa(col[k + 1]) * (c[col[k + 1]] - c_i);
          s2 += w[k + 2] * kappa(col[k + 2]) * (c[col[k + 2]] - c_i);
          s3 += w[k + 3] * kappa(col[k + 3]) * (c[col[k + 3]] - c_i);
        }
      for (; k < m; ++k)
        s0 += w[k] * kappa(col[k]) * (c[col[k]] - c_i);
      return (s0 + s1) + (s2 + s3);
    }
  } // namespace internal
} // namespace PeriDEAL

#endif
