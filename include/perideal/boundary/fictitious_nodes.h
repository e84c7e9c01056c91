#ifndef perideal_boundary_fictitious_nodes_h
#define perideal_boundary_fictitious_nodes_h

#include <deal.II/base/mpi.h>
#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <deal.II/lac/trilinos_sparse_matrix.h>

#include <perideal/discretization/domain.h>

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  namespace Boundary
  {
    using namespace dealii;

    /**
     * The three ways of imposing a local boundary condition on steady PD
     * diffusion through the fictitious region Gamma (paper 004, Sect. 3):
     * naive (fictitious value = boundary value, or dropped for Neumann),
     * Taylor (per bond, (6)-(9), with the stabilization (7)) and mirror
     * (per fictitious node, (10)-(12), mirror nodes from Sect. 3.4).
     */
    enum class FictitiousNodeMethod
    {
      naive,
      taylor,
      mirror
    };

    /** Parse "naive", "taylor" or "mirror"; throws ParameterError otherwise. */
    FictitiousNodeMethod
    parse_fictitious_node_method(const std::string &name,
                                 const std::string &parameter = "Fictitious node method");

    /** The name used in parameter files. */
    std::string
    to_string(const FictitiousNodeMethod method);

    /** A straight crack from a to b (2D). */
    struct Crack
    {
      Point<2> a, b;
    };

    /**
     * True if the closed segments [p, q] and [c.a, c.b] intersect (a bond
     * touching a crack, e.g. at its tip, counts as cut).
     */
    bool
    crosses(const Point<2> &p, const Point<2> &q, const Crack &c);

    /**
     * A local boundary condition at a boundary point: u = value (Dirichlet),
     * or grad u . n = value + alpha u with n the OUTWARD unit normal (Robin;
     * Neumann for alpha = 0).
     */
    struct LocalCondition
    {
      enum Type
      {
        dirichlet,
        robin
      } type       = dirichlet;
      double value = 0.;
      double alpha = 0.;

      static LocalCondition
      make_dirichlet(const double u)
      {
        return {dirichlet, u, 0.};
      }
      static LocalCondition
      make_neumann(const double flux)
      {
        return {robin, flux, 0.};
      }
    };

    /** The boundary data: the condition at a point of (or near) the boundary. */
    template <int dim>
    using BoundaryData = std::function<LocalCondition(const Point<dim> &)>;

    /**
     * Time-dependent boundary data of a transient run: the type and alpha of
     * the condition at a point must not change in time (they are read when
     * the operator is assembled); the value may.
     */
    template <int dim>
    using TransientBoundaryData = std::function<LocalCondition(const Point<dim> &, const double)>;

    /** A volumetric source f(x, t) of du/dt = L u + f. */
    template <int dim>
    using TransientSource = std::function<double(const Point<dim> &, const double)>;

    /**
     * Row-wise Gershgorin bound of forward Euler u <- u + dt (A u - b + f)
     * with the assembled FNM operator A (as SurfaceNodeRod::GershgorinBound):
     * every disc of I + dt A lies in [-1, 1] iff
     * dt <= 2 / (|a_ii| + sum_j |a_ij|) for all rows and every row is
     * diagonally dominant (sum_j |a_ij| <= |a_ii|, independent of dt).
     */
    struct FnmTimeStepBound
    {
      double time_step = 0.;
      /** The domain node of the limiting row. */
      unsigned int node = 0;
      /** Every row is diagonally dominant (the discs also stay <= 1). */
      bool diagonally_dominant = true;
    };

    /**
     * What the mirror FNM does for a fictitious node without mirror node
     * (sharp convex corners, Sect. 3.4 of paper 004): the naive FNM, or the
     * average of the constraints of the surrounding mirrored fictitious
     * nodes (the closest lattice ring holding any).
     */
    enum class CornerFallback
    {
      naive,
      average
    };

    /** Parameters of a FictitiousNodeProblem. */
    struct FictitiousNodeParameters
    {
      /** Lattice spacing dx (> 0); the lattice is cell centered. */
      double dx = 0.01;
      /** Horizon delta (>= dx). */
      double delta = 0.04;
      FictitiousNodeMethod method = FictitiousNodeMethod::mirror;
      /** lambda of the stabilized Taylor FNM (7) (>= 1; paper: 1.5). */
      double taylor_lambda = 1.5;
      /** Fallback of the mirror FNM for fictitious nodes without mirror. */
      CornerFallback corner_fallback = CornerFallback::naive;
      /** Relative GMRES residual tolerance (in (0, 1)). */
      double tolerance = 1e-11;
    };

    /**
     * One fictitious node of the mirror FNM (Sect. 3.4 of paper 004): a node
     * of the collar Gamma, or a domain node seen from across a crack.
     */
    template <int dim>
    struct FictitiousNode
    {
      /** Index of the node in FictitiousNodeProblem's node arrays. */
      unsigned int node = 0;
      /** True for a domain node acting as fictitious across a crack. */
      bool across_crack = false;
      /** The generalized normal n_Gamma of (16), pointing into the domain. */
      Tensor<1, dim> normal;
      /** The closest domain node x_c on the normal line (invalid: none). */
      unsigned int closest = numbers::invalid_unsigned_int;
      /** The ideal mirror point q and the boundary point x_b (midpoint). */
      Point<dim> mirror_point, boundary_point;
      /** The mirror node x_m: the domain node closest to q (invalid: none). */
      unsigned int mirror = numbers::invalid_unsigned_int;
    };

    /**
     * Steady PD diffusion (004, (4) / (A.1)) with kernel A / |xi|^2 on a
     * cell-centered lattice,
     * @f[ \sum_{j \in H_i} \frac{\beta_{ij} V_j}{|\xi_{ij}|^2} (u_j - u_i) = 0, @f]
     * with local boundary conditions imposed through the fictitious collar
     * Gamma of width delta around the body (the Discretization's volume
     * constraint layer) and through the crack faces: a bond that crosses a
     * crack is not used, and the node across the crack supplies a
     * fictitious value instead (crack faces are insulated).
     *
     * The nodes come from Discretization::setup (domain + layer) and are
     * gathered on every rank, so the geometric step (index function (14),
     * generalized normals (15)-(16), mirror nodes) is replicated and its
     * result independent of the rank count; the fictitious relations are
     * eliminated into the rows of the domain nodes, which are distributed
     * over the ranks as one Trilinos matrix (in the numbering of node ids)
     * and solved by GMRES with an AMG preconditioner.
     */
    template <int dim>
    class FictitiousNodeProblem
    {
    public:
      /**
       * Set up the lattice for the body @p domain (which must have a signed
       * distance) with @p cracks, and run the mirror-node algorithm.
       */
      FictitiousNodeProblem(const MPI_Comm                  comm,
                            const Domain<dim>              &domain,
                            const std::vector<Crack>       &cracks,
                            const FictitiousNodeParameters &parameters);

      /** Solve the steady problem with the boundary data @p bc. */
      void
      solve(const BoundaryData<dim> &bc);

      /**
       * Transient PD diffusion du/dt = L u + f (unit diffusivity, the steady
       * operator of solve()) by @p n_steps forward Euler steps of size @p dt
       * from the current #solution at time @p t (advanced on return). The
       * FNM operator is assembled from bc(., t) at the first call after
       * construction or change_domain() and reused (the types and alphas of
       * the conditions must not change in time); @p dt must not exceed the
       * Gershgorin bound of that operator (ParameterError).
       */
      void
      advance(const TransientBoundaryData<dim> &bc,
              const TransientSource<dim>       &source,
              double                      &t,
              const double                 dt,
              const unsigned int           n_steps);

      /** The Gershgorin bound of forward Euler for the operator with data @p bc. */
      FnmTimeStepBound
      gershgorin_time_step(const BoundaryData<dim> &bc) const;

      /**
       * The critical forward Euler step from the eigenvalues of the operator
       * (dense LAPACK, small problems only): the largest dt with
       * |1 + dt lambda| <= 1 for all eigenvalues lambda (0 if one has a
       * positive real part).
       */
      double
      eigenvalue_time_step(const BoundaryData<dim> &bc) const;

      /**
       * The body changes (corrosion / phase change: the nodes outside
       * @p new_body leave it; fracture: @p new_cracks are added). @p new_body
       * (nullptr: unchanged) must lie inside the current body and outlive
       * this object. The nodes leaving the body become fictitious; the index
       * function (14), the normals (15)-(16) and the mirror nodes are
       * recomputed for the nodes within two horizons of a change (farther,
       * none of them can change), and the solution is kept on the remaining
       * nodes. Returns the number of fictitious nodes whose mirror data were
       * recomputed.
       */
      unsigned int
      change_domain(const Domain<dim> *new_body, const std::vector<Crack> &new_cracks = {});

      /** @name Nodes (replicated, sorted by lattice id) */
      /** @{ */
      std::vector<Point<dim>> position;
      /** True for nodes of the body, false for collar nodes. */
      std::vector<bool> in_domain;
      /** The index function r of (14) (domain nodes; 0 on the collar). */
      std::vector<double> index_function;
      /** The solution on the domain nodes (NaN on collar nodes). */
      std::vector<double> solution;
      /** @} */

      /** The fictitious nodes with their mirror data. */
      std::vector<FictitiousNode<dim>> fictitious;

      /** Number of domain nodes (unknowns). */
      unsigned int
      n_unknowns() const
      {
        return n_domain;
      }
      /** GMRES iterations of the last solve. */
      unsigned int last_iterations = 0;
      /** Wall time of the last solve (assembly + solver) [s]. */
      double last_solve_seconds = 0.;

      /** Node index at lattice position @p index, or invalid. */
      unsigned int
      node_at(const std::array<int, dim> &index) const;

      /** The generalized normal (15)-(16) at an arbitrary node (used by tests). */
      Tensor<1, dim>
      generalized_normal(const unsigned int node, const bool across_crack) const;

      /** Value at @p p: the node value, or the mean of the 4 nearest domain nodes. */
      double
      value_at(const Point<dim> &p) const;

      /**
       * The collar nodes whose mirror constraints are averaged for the
       * unmirrored fictitious node @p node (CornerFallback::average; empty:
       * naive).
       */
      std::vector<unsigned int>
      corner_average_sources(const unsigned int node) const;

      const FictitiousNodeParameters &
      parameters() const
      {
        return prm;
      }

    private:
      /** A bond of the lattice: offset, weight beta V / |xi|^2, |offset|^2 in lattice units. */
      struct Bond
      {
        std::array<int, dim> offset;
        double               weight;
        double               length2;
      };
      /** The node at lattice[k] + offset, or invalid. */
      unsigned int
      neighbor(const unsigned int k, const std::array<int, dim> &offset) const;
      /** True if the segment between nodes crosses a crack. */
      bool
      cut(const unsigned int i, const unsigned int j) const;
      /** The closest boundary point of an outside point (signed distance projection). */
      Point<dim>
      project(const Point<dim> &p) const;
      /** The boundary point on the segment from inside @p a to outside @p b. */
      Point<dim>
      intersect(const Point<dim> &a, const Point<dim> &b) const;
      /** Node j belongs to H^Omega of k (and, if side is valid, is connected to side). */
      bool
      in_omega_part(const unsigned int k, const unsigned int j, const bool across_crack,
                    const unsigned int side) const;
      /** (15)-(16) restricted to the nodes connected to @p side (invalid: all). */
      Tensor<1, dim>
      generalized_normal(const unsigned int k, const bool across_crack, const unsigned int side) const;
      /** Sect. 3.4 steps 2a-2c for fictitious node k (H^Omega restricted to @p side). */
      FictitiousNode<dim>
      make_mirror(const unsigned int k, const bool across, const unsigned int side) const;
      /** (14) for the nodes flagged in @p which (all if empty). */
      void
      compute_index_function(const std::vector<bool> &which = {});
      /** Sect. 3.4 for the nodes flagged in @p which (all if empty; others keep their data). */
      unsigned int
      compute_mirror_nodes(const std::vector<bool> &which = {});

      /**
       * The assembled operator of the rows [begin, end) of the unknowns:
       * sum_j rows_ij u_j - b_i, with b_i = sum of coefficient * value(point)
       * over the data terms of row i (linear in the boundary values, so
       * time-dependent data only re-evaluate the terms).
       */
      struct Operator
      {
        unsigned int                                 begin = 0, end = 0;
        std::vector<std::map<unsigned int, double>> rows;
        struct DataTerm
        {
          unsigned int row;
          Point<dim>   point;
          double       coefficient;
        };
        std::vector<DataTerm> data;
      };
      Operator
      assemble(const BoundaryData<dim> &bc) const;
      /** The forward Euler operator of advance(), reset by change_domain(). */
      struct TransientOperator
      {
        Operator                       op;
        FnmTimeStepBound               bound;
        TrilinosWrappers::SparseMatrix matrix;
        std::vector<unsigned int>      node_of_row;
      };
      std::shared_ptr<TransientOperator> transient;
      /** Scatter the owned unknowns of @p x (all ranks) into #solution. */
      void
      gather_solution(const std::vector<double> &owned_values, const unsigned int begin);

      MPI_Comm                 comm;
      const Domain<dim>       *domain;
      std::vector<Crack>       cracks;
      FictitiousNodeParameters prm;
      std::array<int, dim>     n_lattice;
      Point<dim>               origin;
      /** Node index of each lattice point (invalid: none). */
      std::vector<unsigned int> node_of_lattice;
      std::vector<std::array<int, dim>> lattice;
      /** Unknown number of each domain node. */
      std::vector<unsigned int> unknown;
      unsigned int              n_domain = 0;
      /** Nodes within delta + dx of a crack (bond cuts are only tested there). */
      std::vector<bool> near_crack;
      /** Index into fictitious per node (collar role / crack role). */
      std::vector<unsigned int> fictitious_of_node, crack_fictitious_of_node;
      int                       reach = 0;
      /** The bonds of a full family (weight > 0). */
      std::vector<Bond> bonds;
    };
  } // namespace Boundary
} // namespace PeriDEAL

#endif
