#include <deal.II/base/index_set.h>
#include <deal.II/base/timer.h>

#include <deal.II/lac/lapack_full_matrix.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/solver_gmres.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_sparsity_pattern.h>
#include <deal.II/lac/trilinos_vector.h>

#include <perideal/base/exceptions.h>
#include <perideal/base/kernel.h>
#include <perideal/boundary/fictitious_nodes.h>
#include <perideal/discretization/discretization.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <map>

namespace PeriDEAL
{
  namespace Boundary
  {
    FictitiousNodeMethod
    parse_fictitious_node_method(const std::string &name, const std::string &parameter)
    {
      if (name == "naive")
        return FictitiousNodeMethod::naive;
      if (name == "taylor")
        return FictitiousNodeMethod::taylor;
      if (name == "mirror")
        return FictitiousNodeMethod::mirror;
      check_parameter(false, parameter, name, "naive, taylor or mirror");
      return FictitiousNodeMethod::mirror;
    }

    std::string
    to_string(const FictitiousNodeMethod method)
    {
      switch (method)
        {
          case FictitiousNodeMethod::naive:
            return "naive";
          case FictitiousNodeMethod::taylor:
            return "taylor";
          default:
            return "mirror";
        }
    }

    namespace
    {
      double
      orientation(const Point<2> &a, const Point<2> &b, const Point<2> &c)
      {
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
      }

      /** c is on the closed segment [a, b], given that the three are collinear. */
      bool
      on_segment(const Point<2> &a, const Point<2> &b, const Point<2> &c, const double tol)
      {
        return std::min(a[0], b[0]) - tol <= c[0] && c[0] <= std::max(a[0], b[0]) + tol &&
               std::min(a[1], b[1]) - tol <= c[1] && c[1] <= std::max(a[1], b[1]) + tol;
      }

      /** All offsets of the cube [-radius, radius]^dim. */
      template <int dim>
      std::vector<std::array<int, dim>>
      cube(const int radius)
      {
        std::vector<std::array<int, dim>> offsets;
        const int                         n     = 2 * radius + 1;
        int                               total = 1;
        for (int d = 0; d < dim; ++d)
          total *= n;
        for (int k = 0; k < total; ++k)
          {
            std::array<int, dim> o;
            for (int d = 0, rest = k; d < dim; ++d, rest /= n)
              o[d] = rest % n - radius;
            offsets.push_back(o);
          }
        return offsets;
      }

      template <int dim>
      double
      norm2(const std::array<int, dim> &o)
      {
        double s = 0.;
        for (const int v : o)
          s += double(v) * v;
        return s;
      }

      /** Position of a lattice index in the flat array (first direction fastest). */
      template <int dim>
      std::size_t
      flat(const std::array<int, dim> &index, const std::array<int, dim> &n)
      {
        std::size_t k = 0;
        for (int d = dim - 1; d >= 0; --d)
          k = k * n[d] + index[d];
        return k;
      }

      double
      distance_to_segment(const Point<2> &p, const Crack &c)
      {
        const Tensor<1, 2> t  = c.b - c.a;
        const double       l2 = t * t;
        const double s = l2 > 0 ? std::clamp(((p - c.a) * t) / l2, 0., 1.) : 0.;
        return p.distance(c.a + s * t);
      }
    } // namespace

    bool
    crosses(const Point<2> &p, const Point<2> &q, const Crack &c)
    {
      const double scale = std::max(p.distance(q), c.a.distance(c.b));
      const double tol   = 1e-12 * scale * scale;
      const double d1 = orientation(c.a, c.b, p), d2 = orientation(c.a, c.b, q);
      const double d3 = orientation(p, q, c.a), d4 = orientation(p, q, c.b);
      if (((d1 > tol && d2 < -tol) || (d1 < -tol && d2 > tol)) &&
          ((d3 > tol && d4 < -tol) || (d3 < -tol && d4 > tol)))
        return true;
      const double ltol = 1e-12 * scale;
      return (std::abs(d1) <= tol && on_segment(c.a, c.b, p, ltol)) ||
             (std::abs(d2) <= tol && on_segment(c.a, c.b, q, ltol)) ||
             (std::abs(d3) <= tol && on_segment(p, q, c.a, ltol)) ||
             (std::abs(d4) <= tol && on_segment(p, q, c.b, ltol));
    }

    template <int dim>
    FictitiousNodeProblem<dim>::FictitiousNodeProblem(const MPI_Comm                  comm,
                                                 const Domain<dim>              &domain,
                                                 const std::vector<Crack>       &cracks,
                                                 const FictitiousNodeParameters &parameters)
      : comm(comm)
      , domain(&domain)
      , cracks(cracks)
      , prm(parameters)
    {
      check_parameter(prm.dx > 0., "Grid spacing", prm.dx, "a positive number");
      check_parameter(prm.delta >= prm.dx * (1. - 1e-12), "Horizon", prm.delta, ">= Grid spacing");
      check_parameter(prm.taylor_lambda >= 1., "Taylor lambda", prm.taylor_lambda, ">= 1");
      check_parameter(prm.tolerance > 0. && prm.tolerance < 1., "Solver tolerance", prm.tolerance,
                      "(0, 1)");
      check_parameter(domain.has_signed_distance(), "Geometry", "a domain without signed distance",
                      "a domain with a signed distance (box, ball, level set)");
      for (const auto &c : cracks)
        check_parameter(c.a.distance(c.b) > 0., "Crack", "a zero-length crack",
                        "segments of positive length");
      check_parameter(dim == 2 || cracks.empty(), "Crack", "a crack in 3D", "cracks in 2D only");

      // The lattice of the body plus the collar Gamma (the volume constraint
      // layer, one extra step wide so that every bond of a domain node ends
      // on a node), generated and distributed by the Discretization.
      Discretization<dim> disc(comm);
      LatticeParameters lp;
      lp.dx              = prm.dx;
      lp.delta           = prm.delta;
      lp.partial_volume  = true;
      lp.cell_centered   = true;
      lp.layer_thickness = prm.delta + prm.dx;
      disc.setup(domain, lp);

      // Gathered as (index_0 .. index_dim-1, interior) and sorted with the
      // last lattice direction slowest.
      std::vector<int> mine;
      for (unsigned int i = 0; i < disc.n_owned(); ++i)
        {
          for (unsigned int d = 0; d < dim; ++d)
            mine.push_back(disc.lattice_index[i][d]);
          mine.push_back(disc.region[i] == Discretization<dim>::interior ? 1 : 0);
        }
      std::vector<std::array<int, dim + 1>> all;
      for (const auto &part : Utilities::MPI::all_gather(comm, mine))
        for (unsigned int k = 0; k + dim < part.size(); k += dim + 1)
          {
            std::array<int, dim + 1> a;
            std::copy(part.begin() + k, part.begin() + k + dim + 1, a.begin());
            all.push_back(a);
          }
      std::sort(all.begin(), all.end(), [](const auto &a, const auto &b) {
        for (int d = dim - 1; d >= 0; --d)
          if (a[d] != b[d])
            return a[d] < b[d];
        return false;
      });

      std::size_t n_total = 1;
      for (unsigned int d = 0; d < dim; ++d)
        {
          n_lattice[d] = disc.lattice_size()[d];
          n_total *= n_lattice[d];
        }
      origin = disc.lattice_point(std::array<int, dim>{});
      node_of_lattice.assign(n_total, numbers::invalid_unsigned_int);
      for (const auto &a : all)
        {
          std::array<int, dim> index;
          std::copy(a.begin(), a.begin() + dim, index.begin());
          node_of_lattice[flat<dim>(index, n_lattice)] = position.size();
          position.push_back(disc.lattice_point(index));
          lattice.push_back(index);
          in_domain.push_back(a[dim] == 1);
          unknown.push_back(a[dim] == 1 ? n_domain++ : numbers::invalid_unsigned_int);
        }
      check_parameter(n_domain > 0, "Geometry", "an empty body", "a body containing nodes");

      // Bond weights beta V / |xi|^2 of the kernel (3), times the constant A
      // of the library's kernel (which cancels in the steady problem). beta
      // is the partial volume of (A.1): support up to delta + dx/2.
      ScalarKernel kernel;
      kernel.dim      = dim;
      kernel.exponent = 2.;
      kernel.delta    = prm.delta;
      kernel.constant = kernel.micro_constant_for(1.);
      reach           = int(std::ceil((prm.delta + 0.5 * prm.dx) / prm.dx));
      for (const auto &o : cube<dim>(reach))
        {
          const double length2 = norm2<dim>(o);
          if (length2 == 0.)
            continue;
          const double r    = prm.dx * std::sqrt(length2);
          const double beta = Discretization<dim>::volume_factor(r, prm.delta, prm.dx, true);
          if (beta > 0.)
            bonds.push_back({o, kernel.constant * beta * std::pow(prm.dx, dim) / (r * r), length2});
        }

      near_crack.assign(position.size(), false);
      if constexpr (dim == 2)
        for (unsigned int i = 0; i < position.size(); ++i)
          for (const auto &c : cracks)
            if (distance_to_segment(position[i], c) <= prm.delta + 2. * prm.dx)
              near_crack[i] = true;

      compute_index_function();
      compute_mirror_nodes();
    }

    template <int dim>
    unsigned int
    FictitiousNodeProblem<dim>::node_at(const std::array<int, dim> &index) const
    {
      for (unsigned int d = 0; d < dim; ++d)
        if (index[d] < 0 || index[d] >= n_lattice[d])
          return numbers::invalid_unsigned_int;
      return node_of_lattice[flat<dim>(index, n_lattice)];
    }

    template <int dim>
    unsigned int
    FictitiousNodeProblem<dim>::neighbor(const unsigned int k, const std::array<int, dim> &offset) const
    {
      std::array<int, dim> index = lattice[k];
      for (unsigned int d = 0; d < dim; ++d)
        index[d] += offset[d];
      return node_at(index);
    }

    template <int dim>
    bool
    FictitiousNodeProblem<dim>::cut(const unsigned int i, const unsigned int j) const
    {
      if (!near_crack[i] && !near_crack[j])
        return false;
      if constexpr (dim == 2)
        for (const auto &c : cracks)
          if (crosses(position[i], position[j], c))
            return true;
      return false;
    }

    template <int dim>
    void
    FictitiousNodeProblem<dim>::compute_index_function(const std::vector<bool> &which)
    {
      // (14) with the discrete full-horizon volume as denominator, so that
      // r = 1 exactly for nodes with a complete, uncut family. The volume
      // of bond (a, b) is weight * |xi|^2 (the weights carry 1/|xi|^2).
      double full = 0.;
      for (const auto &bond : bonds)
        full += bond.weight * bond.length2;
      index_function.resize(position.size(), 0.);
      for (unsigned int i = 0; i < position.size(); ++i)
        if (which.empty() || which[i])
          {
            index_function[i] = 0.;
            if (!in_domain[i])
              continue;
            double inside = 0.;
            for (const auto &bond : bonds)
              {
                const unsigned int j = neighbor(i, bond.offset);
                if (j != numbers::invalid_unsigned_int && in_domain[j] && !cut(i, j))
                  inside += bond.weight * bond.length2;
              }
            index_function[i] = inside / full;
          }
    }

    template <int dim>
    Tensor<1, dim>
    FictitiousNodeProblem<dim>::generalized_normal(const unsigned int k, const bool across_crack) const
    {
      return generalized_normal(k, across_crack, numbers::invalid_unsigned_int);
    }

    template <int dim>
    bool
    FictitiousNodeProblem<dim>::in_omega_part(const unsigned int k,
                                         const unsigned int j,
                                         const bool         across_crack,
                                         const unsigned int side) const
    {
      return in_domain[j] && cut(k, j) == across_crack &&
             (side == numbers::invalid_unsigned_int || j == side || !cut(side, j));
    }

    template <int dim>
    Tensor<1, dim>
    FictitiousNodeProblem<dim>::generalized_normal(const unsigned int k,
                                              const bool         across_crack,
                                              const unsigned int side) const
    {
      // (15): the PD gradient of r over the domain part H^Omega of the
      // family (connected domain nodes; for a node seen across a crack, the
      // disconnected ones), with partial volumes; (16): normalized.
      Tensor<1, dim> g;
      for (const auto &bond : bonds)
        {
          const unsigned int j = neighbor(k, bond.offset);
          if (j == numbers::invalid_unsigned_int || !in_omega_part(k, j, across_crack, side))
            continue;
          g += bond.weight * index_function[j] * (position[j] - position[k]);
        }
      const double norm = g.norm();
      return norm > 0. ? g / norm : Tensor<1, dim>();
    }

    template <int dim>
    unsigned int
    FictitiousNodeProblem<dim>::compute_mirror_nodes(const std::vector<bool> &which)
    {
      const std::vector<FictitiousNode<dim>> old = std::move(fictitious);
      const std::vector<unsigned int>   old_of_node = std::move(fictitious_of_node),
                                      old_crack_of_node = std::move(crack_fictitious_of_node);
      fictitious.clear();
      fictitious_of_node.assign(position.size(), numbers::invalid_unsigned_int);
      crack_fictitious_of_node.assign(position.size(), numbers::invalid_unsigned_int);
      unsigned int n_computed = 0;
      for (unsigned int k = 0; k < position.size(); ++k)
        for (const bool across : {false, true})
          {
            auto &of_node = across ? crack_fictitious_of_node : fictitious_of_node;
            if (!which.empty() && !which[k])
              {
                // Unaffected by the change: keep the node's role and data.
                const unsigned int f = (across ? old_crack_of_node : old_of_node)[k];
                if (f != numbers::invalid_unsigned_int)
                  {
                    of_node[k] = fictitious.size();
                    fictitious.push_back(old[f]);
                  }
                continue;
              }
            // Is k fictitious in this role: a collar node bonded to a domain
            // node, or a domain node with a cut bond?
            if (across != bool(in_domain[k]))
              continue;
            bool needed = false;
            for (unsigned int b = 0; b < bonds.size() && !needed; ++b)
              {
                const unsigned int j = neighbor(k, bonds[b].offset);
                needed = j != numbers::invalid_unsigned_int && in_domain[j] && cut(k, j) == across;
              }
            if (!needed)
              continue;

            of_node[k] = fictitious.size();
            fictitious.push_back(make_mirror(k, across, numbers::invalid_unsigned_int));
            ++n_computed;
          }
      return n_computed;
    }

    template <int dim>
    FictitiousNode<dim>
    FictitiousNodeProblem<dim>::make_mirror(const unsigned int k, const bool across, const unsigned int side) const
    {
      const double dx = prm.dx;
      // The paper's (2D) tube radius dx/2 around the normal line; in 3D a
      // line parallel to an axis through a cell center is dx/sqrt(2) from
      // its nearest nodes, hence dx sqrt(dim - 1) / 2.
      const double tube = 0.5 * dx * std::sqrt(double(dim - 1));
            FictitiousNode<dim> f;
            f.node         = k;
            f.across_crack = across;
            f.normal       = generalized_normal(k, across, side);
            if (f.normal.norm() > 0.)
              {
                // The closest node of H^Omega within dx/2 of the normal line.
                double best = std::numeric_limits<double>::max();
                for (const auto &bond : bonds)
                  {
                    const unsigned int j = neighbor(k, bond.offset);
                    if (j == numbers::invalid_unsigned_int || !in_omega_part(k, j, across, side))
                      continue;
                    const Tensor<1, dim> xi = position[j] - position[k];
                    const double         t  = xi * f.normal;
                    if (t <= 0. || (xi - t * f.normal).norm() >= tube * (1. + 1e-9))
                      continue;
                    if (xi.norm() < best * (1. - 1e-12))
                      {
                        best      = xi.norm();
                        f.closest = j;
                      }
                  }
              }
            if (f.closest != numbers::invalid_unsigned_int)
              {
                const double d   = position[f.closest].distance(position[k]);
                f.boundary_point = position[k] + (d - 0.5 * dx) * f.normal;
                f.mirror_point   = position[k] + (2. * d - dx) * f.normal;
                // The domain node closest to q on the side of x_c.
                std::array<int, dim> c;
                for (unsigned int d = 0; d < dim; ++d)
                  c[d] = int(std::lround((f.mirror_point[d] - origin[d]) / dx));
                double best = std::numeric_limits<double>::max();
                for (const auto &o : cube<dim>(2))
                    {
                      std::array<int, dim> index = c;
                      for (unsigned int d = 0; d < dim; ++d)
                        index[d] += o[d];
                      const unsigned int j = node_at(index);
                      if (j == numbers::invalid_unsigned_int || !in_domain[j])
                        continue;
                      const double dist = position[j].distance(f.mirror_point);
                      if (dist < best * (1. - 1e-12) && dist <= dx * (1. + 1e-9) &&
                          (j == f.closest || !cut(f.closest, j)))
                        {
                          best     = dist;
                          f.mirror = j;
                        }
                    }
              }
      return f;
    }

    template <int dim>
    Point<dim>
    FictitiousNodeProblem<dim>::project(const Point<dim> &p) const
    {
      const double h = 1e-6 * prm.dx;
      Tensor<1, dim> grad;
      for (unsigned int d = 0; d < dim; ++d)
        {
          Point<dim> a = p, b = p;
          a[d] += h;
          b[d] -= h;
          grad[d] = (domain->signed_distance(a) - domain->signed_distance(b)) / (2. * h);
        }
      const double n = grad.norm();
      return n > 0. ? Point<dim>(p - domain->signed_distance(p) * grad / n) : p;
    }

    template <int dim>
    Point<dim>
    FictitiousNodeProblem<dim>::intersect(const Point<dim> &a, const Point<dim> &b) const
    {
      double lo = 0., hi = 1.;
      for (unsigned int it = 0; it < 60; ++it)
        {
          const double mid = 0.5 * (lo + hi);
          if (domain->signed_distance(a + mid * (b - a)) <= 0.)
            lo = mid;
          else
            hi = mid;
        }
      return a + 0.5 * (lo + hi) * (b - a);
    }

    template <int dim>
    typename FictitiousNodeProblem<dim>::Operator
    FictitiousNodeProblem<dim>::assemble(const BoundaryData<dim> &bc) const
    {
      Operator           op;
      const unsigned int n_ranks = Utilities::MPI::n_mpi_processes(comm);
      const unsigned int rank    = Utilities::MPI::this_mpi_process(comm);
      const unsigned int begin   = std::size_t(n_domain) * rank / n_ranks;
      const unsigned int end     = std::size_t(n_domain) * (rank + 1) / n_ranks;
      op.begin                     = begin;
      op.end                       = end;
      op.rows.resize(end - begin);
      const double lambda = prm.taylor_lambda;

      for (unsigned int i = 0; i < position.size(); ++i)
        {
          if (!in_domain[i] || unknown[i] < begin || unknown[i] >= end)
            continue;
          auto &row = op.rows[unknown[i] - begin];
          // Each bond adds w (u_eff - u_i) with u_eff = sum c_k u_k + d:
          // stored as row += w c, b -= w d (d = coefficient * boundary value).
          const auto b_minus = [&](const Point<dim> &p, const double coefficient) {
            op.data.push_back({unknown[i] - begin, p, -coefficient});
          };
          // row += w u_G for a mirrored fictitious node f.
          const auto add_mirror_value = [&](const FictitiousNode<dim> &f, const double w) {
            const LocalCondition c = bc(f.boundary_point);
            if (c.type == LocalCondition::dirichlet)
              {
                // (10): u_G = 2 u_b - u_m.
                row[unknown[f.mirror]] -= w;
                b_minus(f.boundary_point, 2. * w);
              }
            else
              {
                // (11)-(12), outward flux g + alpha u at the midpoint:
                // u_G (1 - L alpha/2) = u_m (1 + L alpha/2) + L g.
                const double L   = position[f.node].distance(position[f.mirror]);
                const double den = 1. - 0.5 * L * c.alpha;
                row[unknown[f.mirror]] += w * (1. + 0.5 * L * c.alpha) / den;
                b_minus(f.boundary_point, w * L / den);
              }
          };
          const auto naive = [&](const unsigned int j, const double w) {
            const Point<dim>     p = project(position[j]);
            const LocalCondition c = bc(p);
            if (c.type == LocalCondition::dirichlet)
              {
                row[unknown[i]] -= w;
                b_minus(p, w);
              }
          };
          for (const auto &bond : bonds)
              {
                const double       w = bond.weight;
                const unsigned int j = neighbor(i, bond.offset);
                if (j == numbers::invalid_unsigned_int)
                  continue;
                const bool is_cut = cut(i, j);
                if (in_domain[j] && !is_cut)
                  {
                    row[unknown[j]] += w;
                    row[unknown[i]] -= w;
                    continue;
                  }
                if (in_domain[j])
                  {
                    // Across a crack (insulated): the mirror FNM uses the
                    // fictitious value u_m of (11) with zero flux; naive and
                    // Taylor drop the bond (their zero-flux form).
                    // The mirror is searched among the nodes on the side of
                    // row i (make_mirror with side i): with one straight crack
                    // this is the paper's per-node mirror; at crossing cracks
                    // a node is fictitious for several regions, and one value
                    // per node would couple regions the cracks separate.
                    if (prm.method == FictitiousNodeMethod::mirror)
                      {
                        const FictitiousNode<dim> f = make_mirror(j, true, i);
                        if (f.mirror != numbers::invalid_unsigned_int)
                          {
                            row[unknown[f.mirror]] += w;
                            row[unknown[i]] -= w;
                          }
                      }
                    continue;
                  }
                if (is_cut)
                  continue;
                switch (prm.method)
                  {
                    case FictitiousNodeMethod::naive:
                      naive(j, w);
                      break;
                    case FictitiousNodeMethod::taylor:
                      {
                        const Point<dim>     xb = intersect(position[i], position[j]);
                        const double         dO = position[i].distance(xb);
                        const double         dG = position[j].distance(xb);
                        const LocalCondition c  = bc(xb);
                        if (c.type == LocalCondition::dirichlet)
                          {
                            // (7): u_G - u_i = (u_b - u_i) min(lambda, 1 + dG/dO).
                            const double s = dO > 0. ? std::min(lambda, 1. + dG / dO) : lambda;
                            row[unknown[i]] -= w * s;
                            b_minus(xb, w * s);
                          }
                        else
                          {
                            // (8)-(9) with the inward derivative -(g + alpha u_b):
                            // u_b = (u_i + dO g) / (1 - dO alpha),
                            // u_G - u_i = (dO + dG)(g + alpha u_b).
                            const double den = 1. - dO * c.alpha;
                            row[unknown[i]] += w * (dO + dG) * c.alpha / den;
                            b_minus(xb, w * (dO + dG) / den);
                          }
                        break;
                      }
                    default:
                      {
                        const FictitiousNode<dim> &f = fictitious[fictitious_of_node[j]];
                        if (f.mirror != numbers::invalid_unsigned_int)
                          {
                            row[unknown[i]] -= w;
                            add_mirror_value(f, w);
                            break;
                          }
                        // No mirror (sharp convex corners, Sect. 3.4): the
                        // average of the surrounding fictitious constraints,
                        // or the naive FNM.
                        const auto sources = prm.corner_fallback == CornerFallback::average ?
                                               corner_average_sources(j) :
                                               std::vector<unsigned int>();
                        if (sources.empty())
                          {
                            naive(j, w);
                            break;
                          }
                        row[unknown[i]] -= w;
                        for (const unsigned int g : sources)
                          add_mirror_value(fictitious[fictitious_of_node[g]], w / sources.size());
                      }
                  }
              }
        }

      return op;
    }

    template <int dim>
    std::vector<unsigned int>
    FictitiousNodeProblem<dim>::corner_average_sources(const unsigned int node) const
    {
      // The mirrored collar nodes in the smallest lattice ring around the
      // node that holds any (at most one horizon out).
      std::vector<unsigned int> sources;
      for (int radius = 1; radius <= reach && sources.empty(); ++radius)
        for (const auto &o : cube<dim>(radius))
          {
            int ring = 0;
            for (const int v : o)
              ring = std::max(ring, std::abs(v));
            const unsigned int g = neighbor(node, o);
            if (ring == radius && g != numbers::invalid_unsigned_int && !in_domain[g] &&
                fictitious_of_node[g] != numbers::invalid_unsigned_int &&
                fictitious[fictitious_of_node[g]].mirror != numbers::invalid_unsigned_int)
              sources.push_back(g);
          }
      return sources;
    }

    template <int dim>
    void
    FictitiousNodeProblem<dim>::gather_solution(const std::vector<double> &owned_values, const unsigned int begin)
    {
      std::vector<double> values(n_domain, 0.);
      for (unsigned int u = 0; u < owned_values.size(); ++u)
        values[begin + u] = owned_values[u];
      Utilities::MPI::sum(values, comm, values);
      solution.assign(position.size(), std::numeric_limits<double>::quiet_NaN());
      for (unsigned int i = 0; i < position.size(); ++i)
        if (in_domain[i])
          solution[i] = values[unknown[i]];
    }

    template <int dim>
    void
    FictitiousNodeProblem<dim>::solve(const BoundaryData<dim> &bc)
    {
      Timer          timer;
      const Operator op = assemble(bc);
      const auto    &rows = op.rows;
      const unsigned int begin = op.begin, end = op.end;
      IndexSet       owned(n_domain);
      owned.add_range(begin, end);
      owned.compress();
      std::vector<double> rhs(end - begin, 0.);
      for (const auto &d : op.data)
        rhs[d.row] += d.coefficient * bc(d.point).value;

      // Trilinos matrix (rows negated: positive diagonal) and GMRES + AMG.
      TrilinosWrappers::SparsityPattern sp(owned, owned, comm);
      for (unsigned int r = 0; r < rows.size(); ++r)
        for (const auto &e : rows[r])
          sp.add(begin + r, e.first);
      sp.compress();
      TrilinosWrappers::SparseMatrix matrix;
      matrix.reinit(sp);
      TrilinosWrappers::MPI::Vector x(owned, comm), rhs_vector(owned, comm);
      for (unsigned int r = 0; r < rows.size(); ++r)
        {
          for (const auto &e : rows[r])
            matrix.set(begin + r, e.first, -e.second);
          rhs_vector[begin + r] = -rhs[r];
        }
      matrix.compress(VectorOperation::insert);
      rhs_vector.compress(VectorOperation::insert);

      TrilinosWrappers::PreconditionAMG                 amg;
      TrilinosWrappers::PreconditionAMG::AdditionalData amg_data;
      amg_data.elliptic              = true;
      amg_data.higher_order_elements = false;
      amg_data.smoother_sweeps       = 2;
      amg_data.aggregation_threshold = 0.02;
      amg.initialize(matrix, amg_data);
      SolverControl control(10000, prm.tolerance * rhs_vector.l2_norm());
      SolverGMRES<TrilinosWrappers::MPI::Vector> gmres(
        control, SolverGMRES<TrilinosWrappers::MPI::Vector>::AdditionalData(200));
      gmres.solve(matrix, x, rhs_vector, amg);
      last_iterations = control.last_step();

      std::vector<double> values(end - begin);
      for (unsigned int u = begin; u < end; ++u)
        values[u - begin] = x[u];
      gather_solution(values, begin);
      last_solve_seconds = timer.wall_time();
    }

    template <int dim>
    FnmTimeStepBound
    FictitiousNodeProblem<dim>::gershgorin_time_step(const BoundaryData<dim> &bc) const
    {
      const Operator   op = assemble(bc);
      FnmTimeStepBound g;
      g.time_step         = std::numeric_limits<double>::infinity();
      unsigned int worst  = numbers::invalid_unsigned_int;
      for (unsigned int r = 0; r < op.rows.size(); ++r)
        {
          double diag = 0., radius = 0.;
          for (const auto &e : op.rows[r])
            if (e.first == op.begin + r)
              diag = -e.second;
            else
              radius += std::abs(e.second);
          if (radius > diag * (1. + 1e-12))
            g.diagonally_dominant = false;
          const double bound = 2. / (diag + radius);
          if (bound < g.time_step)
            {
              g.time_step = bound;
              worst       = op.begin + r;
            }
        }
      // The smallest bound over the ranks, and its row (lowest unknown on ties).
      const double global = Utilities::MPI::min(g.time_step, comm);
      const unsigned int row =
        Utilities::MPI::min(g.time_step == global ? worst : numbers::invalid_unsigned_int, comm);
      g.time_step           = global;
      g.diagonally_dominant = Utilities::MPI::min(g.diagonally_dominant ? 1 : 0, comm) == 1;
      for (unsigned int i = 0; i < position.size(); ++i)
        if (in_domain[i] && unknown[i] == row)
          g.node = i;
      return g;
    }

    template <int dim>
    double
    FictitiousNodeProblem<dim>::eigenvalue_time_step(const BoundaryData<dim> &bc) const
    {
      check_parameter(n_domain <= 4000, "Nodes of the eigenvalue check", n_domain, "at most 4000 (dense)");
      const Operator      op = assemble(bc);
      std::vector<double> triplets;
      for (unsigned int r = 0; r < op.rows.size(); ++r)
        for (const auto &e : op.rows[r])
          triplets.insert(triplets.end(), {double(op.begin + r), double(e.first), e.second});
      LAPACKFullMatrix<double> A(n_domain, n_domain);
      for (const auto &part : Utilities::MPI::all_gather(comm, triplets))
        for (unsigned int k = 0; k + 2 < part.size(); k += 3)
          A(std::size_t(part[k]), std::size_t(part[k + 1])) = part[k + 2];
      A.compute_eigenvalues();
      // |1 + dt lambda| <= 1 <=> dt <= -2 Re(lambda) / |lambda|^2.
      double dt = std::numeric_limits<double>::infinity();
      for (unsigned int k = 0; k < n_domain; ++k)
        {
          const std::complex<double> lambda = A.eigenvalue(k);
          if (lambda.real() >= 0.)
            return 0.;
          dt = std::min(dt, -2. * lambda.real() / std::norm(lambda));
        }
      return dt;
    }

    template <int dim>
    void
    FictitiousNodeProblem<dim>::advance(const TransientBoundaryData<dim> &bc,
                                   const TransientSource<dim>       &source,
                                   double                      &t,
                                   const double                 dt,
                                   const unsigned int           n_steps)
    {
      Timer        timer;
      const double t0 = t;
      if (!transient)
        {
          // Assembled at the first call after construction or a domain
          // change: the conditions' types and alphas are fixed in time.
          const BoundaryData<dim> bc_t0 = [&](const Point<dim> &p) { return bc(p, t0); };
          transient              = std::make_shared<TransientOperator>();
          transient->bound       = gershgorin_time_step(bc_t0);
          transient->op          = assemble(bc_t0);
          const Operator &op     = transient->op;
          IndexSet        owned(n_domain);
          owned.add_range(op.begin, op.end);
          owned.compress();
          TrilinosWrappers::SparsityPattern sp(owned, owned, comm);
          for (unsigned int r = 0; r < op.rows.size(); ++r)
            for (const auto &e : op.rows[r])
              sp.add(op.begin + r, e.first);
          sp.compress();
          transient->matrix.reinit(sp);
          for (unsigned int r = 0; r < op.rows.size(); ++r)
            for (const auto &e : op.rows[r])
              transient->matrix.set(op.begin + r, e.first, e.second);
          transient->matrix.compress(VectorOperation::insert);
          // The owned rows' nodes (for the source and the initial values).
          transient->node_of_row.resize(op.end - op.begin);
          for (unsigned int i = 0; i < position.size(); ++i)
            if (in_domain[i] && unknown[i] >= op.begin && unknown[i] < op.end)
              transient->node_of_row[unknown[i] - op.begin] = i;
        }
      const double time_step = transient->bound.time_step;
      check_parameter(dt > 0. && dt <= time_step * (1. + 1e-12), "Time step", dt,
                      "(0, " + std::to_string(time_step) +
                        "], the Gershgorin bound of the forward Euler iteration matrix of the FNM operator");
      const Operator                       &op          = transient->op;
      const TrilinosWrappers::SparseMatrix &A           = transient->matrix;
      const std::vector<unsigned int>      &node_of_row = transient->node_of_row;
      IndexSet                              owned(n_domain);
      owned.add_range(op.begin, op.end);
      owned.compress();
      TrilinosWrappers::MPI::Vector u(owned, comm), Au(owned, comm);
      for (unsigned int r = 0; r < node_of_row.size(); ++r)
        {
          const double value = solution.size() == position.size() ? solution[node_of_row[r]] : 0.;
          check_parameter(std::isfinite(value), "Initial condition", value, "finite values on the domain nodes");
          u[op.begin + r] = value;
        }
      u.compress(VectorOperation::insert);

      std::vector<double> increment(op.rows.size());
      for (unsigned int step = 0; step < n_steps; ++step)
        {
          const double time = t0 + step * dt;
          A.vmult(Au, u);
          for (unsigned int r = 0; r < increment.size(); ++r)
            increment[r] = Au[op.begin + r] + (source ? source(position[node_of_row[r]], time) : 0.);
          for (const auto &d : op.data)
            increment[d.row] -= d.coefficient * bc(d.point, time).value;
          for (unsigned int r = 0; r < increment.size(); ++r)
            u[op.begin + r] += dt * increment[r];
          u.compress(VectorOperation::insert);
        }
      t = t0 + n_steps * dt;
      std::vector<double> values(op.end - op.begin);
      for (unsigned int r = 0; r < values.size(); ++r)
        values[r] = u[op.begin + r];
      gather_solution(values, op.begin);
      last_solve_seconds = timer.wall_time();
    }

    template <int dim>
    unsigned int
    FictitiousNodeProblem<dim>::change_domain(const Domain<dim> *new_body, const std::vector<Crack> &new_cracks)
    {
      std::vector<bool> changed(position.size(), false);
      if (new_body != nullptr)
        {
          check_parameter(new_body->has_signed_distance(), "Geometry", "a domain without signed distance",
                          "a domain with a signed distance (box, ball, level set)");
          for (unsigned int i = 0; i < position.size(); ++i)
            {
              const bool inside = new_body->inside(position[i]);
              check_parameter(in_domain[i] || !inside, "Domain change", "a body growing beyond the current one",
                              "a body inside the current one (nodes can only leave the body)");
              if (in_domain[i] && !inside)
                {
                  in_domain[i] = false;
                  changed[i]   = true;
                }
            }
          domain = new_body;
        }
      transient.reset();
      check_parameter(dim == 2 || new_cracks.empty(), "Crack", "a crack in 3D", "cracks in 2D only");
      for (const auto &c : new_cracks)
        {
          check_parameter(c.a.distance(c.b) > 0., "Crack", "a zero-length crack", "segments of positive length");
          cracks.push_back(c);
          if constexpr (dim == 2)
            for (unsigned int i = 0; i < position.size(); ++i)
              if (distance_to_segment(position[i], c) <= prm.delta + 2. * prm.dx)
                near_crack[i] = changed[i] = true;
        }

      // The index function of a node depends on the nodes within one
      // horizon (reach lattice steps), the normal of a fictitious node on
      // the index function within another, and the mirror node on the nodes
      // within 2 steps of the mirror point (at most 2 horizons away):
      // 2 reach + 3 steps bound the influence of a changed node.
      const int         radius = 2 * reach + 3;
      std::vector<bool> affected(position.size(), false);
      const auto        around = cube<dim>(radius);
      for (unsigned int i = 0; i < position.size(); ++i)
        if (changed[i])
          for (const auto &o : around)
            {
              const unsigned int j = neighbor(i, o);
              if (j != numbers::invalid_unsigned_int)
                affected[j] = true;
            }

      // Renumber the unknowns; the solution stays on the remaining nodes.
      n_domain = 0;
      for (unsigned int i = 0; i < position.size(); ++i)
        {
          unknown[i] = in_domain[i] ? n_domain++ : numbers::invalid_unsigned_int;
          if (!in_domain[i] && i < solution.size())
            solution[i] = std::numeric_limits<double>::quiet_NaN();
        }
      check_parameter(n_domain > 0, "Domain change", "an empty body", "a body containing nodes");

      compute_index_function(affected);
      return compute_mirror_nodes(affected);
    }

    template <int dim>
    double
    FictitiousNodeProblem<dim>::value_at(const Point<dim> &p) const
    {
      std::array<int, dim> lower, nearest;
      bool                 on_node = true;
      for (unsigned int d = 0; d < dim; ++d)
        {
          const double s = (p[d] - origin[d]) / prm.dx;
          lower[d]       = int(std::floor(s));
          nearest[d]     = int(std::lround(s));
          on_node        = on_node && std::abs(s - nearest[d]) < 1e-9;
        }
      if (on_node)
        {
          const unsigned int j = node_at(nearest);
          if (j != numbers::invalid_unsigned_int && in_domain[j])
            return solution[j];
        }
      double sum = 0.;
      int    n   = 0;
      for (unsigned int corner = 0; corner < (1u << dim); ++corner)
        {
          std::array<int, dim> index = lower;
          for (unsigned int d = 0; d < dim; ++d)
            index[d] += (corner >> d) & 1;
          const unsigned int j = node_at(index);
          if (j != numbers::invalid_unsigned_int && in_domain[j])
            {
              sum += solution[j];
              ++n;
            }
        }
      return n > 0 ? sum / n : std::numeric_limits<double>::quiet_NaN();
    }

    template class FictitiousNodeProblem<2>;
    template class FictitiousNodeProblem<3>;
  } // namespace Boundary
} // namespace PeriDEAL
