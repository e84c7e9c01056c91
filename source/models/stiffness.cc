#include <deal.II/base/mpi.h>

#include <deal.II/lac/trilinos_sparsity_pattern.h>

#include <perideal/base/exceptions.h>
#include <perideal/models/stiffness.h>

#include <algorithm>
#include <cmath>

namespace PeriDEAL
{
  namespace Stiffness
  {
    namespace
    {
      /**
       * Node-block assembly helper: global unknowns, the fixed mask, a
       * sparsity pattern that may receive ghost rows, and block-wise adds
       * that drop fixed rows/columns.
       */
      template <int dim>
      class BlockAssembler
      {
      public:
        BlockAssembler(const Discretization<dim>         &disc,
                       const std::vector<unsigned char>  &fixed,
                       const bool                          ghost_rows,
                       const unsigned int                  entries_per_row)
          : disc(disc)
          , fixed(fixed)
          , owned(owned_dofs(disc))
          , writable(owned)
        {
          AssertThrow(fixed.empty() || fixed.size() == disc.n_owned() + disc.n_ghost(),
                      ExcMessage("The fixed mask needs one entry per owned and ghost node."));
          if (ghost_rows)
            for (unsigned int i = disc.n_owned(); i < disc.n_owned() + disc.n_ghost(); ++i)
              for (unsigned int d = 0; d < dim; ++d)
                writable.add_index(dof(i, d));
          writable.compress();
          sp.reinit(owned, owned, writable, disc.get_mpi_communicator(), entries_per_row);
        }

        types::global_dof_index
        dof(const unsigned int local_node, const unsigned int d) const
        {
          return dim * disc.partitioner()->local_to_global(local_node) + d;
        }

        bool
        is_fixed(const unsigned int local_node) const
        {
          return !fixed.empty() && fixed[local_node] != 0;
        }

        /** Declare the coupling of all nodes in @p rows with all in @p cols. */
        void
        add_pattern(const std::vector<unsigned int> &rows, const std::vector<unsigned int> &cols)
        {
          col_dofs.clear();
          for (const unsigned int s : cols)
            if (!is_fixed(s))
              for (unsigned int d = 0; d < dim; ++d)
                col_dofs.push_back(dof(s, d));
          for (const unsigned int t : rows)
            if (!is_fixed(t))
              for (unsigned int d = 0; d < dim; ++d)
                sp.add_entries(dof(t, d), col_dofs.begin(), col_dofs.end());
        }

        /** Finish the pattern, initialize @p matrix, put 1 on fixed owned diagonals. */
        void
        initialize(TrilinosWrappers::SparseMatrix &matrix)
        {
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            if (is_fixed(i))
              for (unsigned int d = 0; d < dim; ++d)
                {
                  const types::global_dof_index r = dof(i, d);
                  sp.add(r, r);
                }
          sp.compress();
          matrix.reinit(sp);
          // add, not set: switching between set and add makes Trilinos
          // assemble globally, a collective call not every rank would make.
          for (unsigned int i = 0; i < disc.n_owned(); ++i)
            if (is_fixed(i))
              for (unsigned int d = 0; d < dim; ++d)
                matrix.add(dof(i, d), dof(i, d), 1.);
        }

        /**
         * K[t, s] += block[k][l] for the rows t in @p rows and columns s in
         * @p cols; @p block(a, b) returns the dim x dim block of rows[a] and
         * cols[b].
         */
        template <typename Block>
        void
        add(TrilinosWrappers::SparseMatrix  &matrix,
            const std::vector<unsigned int> &rows,
            const std::vector<unsigned int> &cols,
            const Block                     &block)
        {
          col_dofs.clear();
          col_index.clear();
          for (unsigned int b = 0; b < cols.size(); ++b)
            if (!is_fixed(cols[b]))
              {
                col_index.push_back(b);
                for (unsigned int d = 0; d < dim; ++d)
                  col_dofs.push_back(dof(cols[b], d));
              }
          values.resize(col_dofs.size());
          for (unsigned int a = 0; a < rows.size(); ++a)
            {
              if (is_fixed(rows[a]))
                continue;
              for (unsigned int d1 = 0; d1 < dim; ++d1)
                {
                  for (unsigned int c = 0; c < col_index.size(); ++c)
                    {
                      const Tensor<2, dim> B = block(a, col_index[c]);
                      for (unsigned int d2 = 0; d2 < dim; ++d2)
                        values[dim * c + d2] = B[d1][d2];
                    }
                  matrix.add(dof(rows[a], d1), col_dofs.size(), col_dofs.data(), values.data(),
                             false, false);
                }
            }
        }

      private:
        const Discretization<dim>            &disc;
        const std::vector<unsigned char>     &fixed;
        IndexSet                              owned, writable;
        TrilinosWrappers::SparsityPattern     sp;
        std::vector<types::global_dof_index>  col_dofs;
        std::vector<unsigned int>             col_index;
        std::vector<double>                   values;
      };

      template <int dim>
      Tensor<1, dim>
      bond_vector(const Discretization<dim> &disc, const unsigned int i, const unsigned int j)
      {
        return disc.position[j] - disc.position[i];
      }
    } // namespace

    template <int dim>
    IndexSet
    owned_dofs(const Discretization<dim> &disc)
    {
      const auto &range = disc.partitioner()->local_range();
      IndexSet    owned(dim * disc.n_global());
      owned.add_range(dim * types::global_dof_index(range.first),
                      dim * types::global_dof_index(range.second));
      owned.compress();
      return owned;
    }

    template <int dim>
    void
    assemble(const BondBasedOperator<dim>     &op,
             TrilinosWrappers::SparseMatrix   &matrix,
             const std::vector<unsigned char> &fixed)
    {
      AssertThrow(op.is_linearized(),
                  ExcMessage("The stiffness matrix exists for the linearized bond-based "
                             "model (2.32) only."));
      const auto &disc = op.discretization();
      const auto &nb   = disc.neighborhood;
      const auto &coef = op.bond_coefficients();
      const auto &br   = op.broken();

      BlockAssembler<dim>       assembler(disc, fixed, false, dim * (nb.stencil_size + 1));
      std::vector<unsigned int> row(1), cols;
      auto family = [&](const unsigned int i) {
        cols.assign(1, i);
        for (std::uint64_t b = nb.row_start[i]; b < nb.row_start[i + 1]; ++b)
          cols.push_back(nb.col[b]);
      };
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          row[0] = i;
          family(i);
          assembler.add_pattern(row, cols);
        }
      assembler.initialize(matrix);

      // Blocks of row i: -C_ij for the neighbours, sum_j C_ij on the diagonal.
      std::vector<Tensor<2, dim>> blocks;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          row[0] = i;
          family(i);
          blocks.assign(cols.size(), Tensor<2, dim>());
          const std::uint64_t begin = nb.row_start[i];
          for (std::uint64_t b = begin; b < nb.row_start[i + 1]; ++b)
            {
              if (br[b])
                continue;
              const Tensor<1, dim> xi = bond_vector(disc, i, nb.col[b]);
              const double         r  = xi.norm();
              const Tensor<2, dim> C =
                coef[nb.table_start[i] + (b - begin)] / (r * r) * outer_product(xi, xi);
              blocks[0] += C;
              blocks[1 + b - begin] -= C;
            }
          assembler.add(matrix, row, cols,
                        [&](unsigned int, unsigned int c) -> const Tensor<2, dim> & {
                          return blocks[c];
                        });
        }
      matrix.compress(VectorOperation::add);
    }

    template <int dim>
    void
    assemble(const LinearizedLPSOperator<dim> &op,
             TrilinosWrappers::SparseMatrix   &matrix,
             const std::vector<unsigned char> &fixed)
    {
      const auto &disc = op.discretization();
      const auto &nb   = disc.neighborhood;
      const auto &coef = op.bond_coefficients();
      const auto &br   = op.broken();
      const auto &m    = op.weighted_volume();
      const double K_d = op.dimensional_bulk_modulus(), G = op.shear_modulus();
      const double a_vol = dim * K_d - (dim + 2.) * G;
      const double a_dev = dim * (dim + 2.) * G;
      auto inv = [](const double x) { return x > 0. ? 1. / x : 0.; };

      // S_j = {j} + family of j; the two-hop stencil has about 2^dim times
      // as many nodes as one family.
      BlockAssembler<dim> assembler(disc, fixed, true,
                                    dim * (nb.stencil_size + 1) * (1u << dim));
      std::vector<unsigned int> family;
      auto set_family = [&](const unsigned int j) {
        family.assign(1, j);
        for (std::uint64_t b = nb.row_start[j]; b < nb.row_start[j + 1]; ++b)
          family.push_back(nb.col[b]);
      };
      for (unsigned int j = 0; j < disc.n_owned(); ++j)
        {
          set_family(j);
          assembler.add_pattern(family, family);
        }
      assembler.initialize(matrix);

      std::vector<Tensor<1, dim>> g, h;
      std::vector<Tensor<2, dim>> dev;
      for (unsigned int j = 0; j < disc.n_owned(); ++j)
        {
          set_family(j);
          const unsigned int  n     = family.size();
          const std::uint64_t begin = nb.row_start[j];
          const double       *c     = coef.data() + nb.table_start[j];
          const double        inv_mj = inv(m.local_element(j));
          // theta_j = sum_s g_s . u_s, and theta_j enters the force of
          // node t as h_t theta_j: h_j = a_vol/m_j sum_k c_jk xi_jk (term
          // theta_i/m_i of (2.18) in row j), and for a neighbour i
          // h_i = a_vol/m_j c_ij xi_ij with c_ij = c_ji V_j / V_i (row i's
          // weight beta V_j).
          g.assign(n, Tensor<1, dim>());
          h.assign(n, Tensor<1, dim>());
          dev.assign(n, Tensor<2, dim>());
          for (std::uint64_t b = begin; b < nb.row_start[j + 1]; ++b)
            {
              if (br[b])
                continue;
              const unsigned int   k  = nb.col[b];
              const unsigned int   s  = 1 + b - begin;
              const Tensor<1, dim> xi = bond_vector(disc, j, k);
              const double         cjk = c[b - begin];
              g[s] = dim * inv_mj * cjk * xi;
              g[0] -= g[s];
              h[0] += a_vol * inv_mj * cjk * xi;
              h[s] = -a_vol * inv_mj * cjk * disc.volume[j] / disc.volume[k] * xi;
              // Deviatoric pair force of row j: f_j += D (u_k - u_j).
              const Tensor<2, dim> D = a_dev * (inv_mj + inv(m.local_element(k))) * cjk /
                                       (xi * xi) * outer_product(xi, xi);
              dev[0] += D;
              dev[s] -= D;
            }
          // K = -df/du: -h_t (x) g_s over the family, plus row j's pair part.
          assembler.add(matrix, family, family, [&](unsigned int a, unsigned int b) {
            Tensor<2, dim> B = -outer_product(h[a], g[b]);
            if (a == 0)
              B += dev[b];
            return B;
          });
        }
      matrix.compress(VectorOperation::add);
    }

    template <int dim>
    void
    to_dofs(const Discretization<dim>     &disc,
            const std::array<Vector, std::size_t(dim)> &field,
            TrilinosWrappers::MPI::Vector &v)
    {
      const auto range = disc.partitioner()->local_range();
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        for (unsigned int d = 0; d < dim; ++d)
          v[dim * types::global_dof_index(range.first + i) + d] = field[d].local_element(i);
      v.compress(VectorOperation::insert);
    }

    template <int dim>
    void
    from_dofs(const Discretization<dim>           &disc,
              const TrilinosWrappers::MPI::Vector &v,
              std::array<Vector, std::size_t(dim)>             &field)
    {
      const auto range = disc.partitioner()->local_range();
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        for (unsigned int d = 0; d < dim; ++d)
          field[d].local_element(i) = v[dim * types::global_dof_index(range.first + i) + d];
      for (auto &f : field)
        f.update_ghost_values();
    }

    double
    gershgorin_bound(const TrilinosWrappers::SparseMatrix &matrix)
    {
      double bound = 0.;
      for (const auto r : matrix.locally_owned_range_indices())
        {
          double s = 0.;
          for (auto e = matrix.begin(r); e != matrix.end(r); ++e)
            s += std::abs(e->value());
          bound = std::max(bound, s);
        }
      return Utilities::MPI::max(bound, matrix.get_mpi_communicator());
    }

    double
    critical_time_step(const TrilinosWrappers::SparseMatrix &matrix, const double rho)
    {
      check_parameter(rho > 0., "density", rho, "a positive number");
      return 2. * std::sqrt(rho / gershgorin_bound(matrix));
    }

#define PERIDEAL_INSTANTIATE(dim)                                                              \
  template IndexSet owned_dofs(const Discretization<dim> &);                                   \
  template void     to_dofs(const Discretization<dim> &, const std::array<Vector, std::size_t(dim)> &,      \
                        TrilinosWrappers::MPI::Vector &);                                      \
  template void     from_dofs(const Discretization<dim> &, const TrilinosWrappers::MPI::Vector &, \
                          std::array<Vector, std::size_t(dim)> &);                                          \
  template void     assemble(const BondBasedOperator<dim> &, TrilinosWrappers::SparseMatrix &,   \
                         const std::vector<unsigned char> &);

    PERIDEAL_INSTANTIATE(1)
    PERIDEAL_INSTANTIATE(2)
    PERIDEAL_INSTANTIATE(3)
#undef PERIDEAL_INSTANTIATE
    template void
    assemble(const LinearizedLPSOperator<2> &, TrilinosWrappers::SparseMatrix &,
             const std::vector<unsigned char> &);
    template void
    assemble(const LinearizedLPSOperator<3> &, TrilinosWrappers::SparseMatrix &,
             const std::vector<unsigned char> &);
  } // namespace Stiffness
} // namespace PeriDEAL
