// FEM near fields with EBF absorbing boundaries on parallel::distributed
// triangulations and on disks (issue 4, "FEM near field"): the result on 2
// ranks equals the serial one (clouds straddle the rank boundary; compared
// DoF by DoF through the support points), and the disk near fields are
// compared with the heat kernel (diffusion) and with an extended disk
// (waves) against Neumann / first-order truncation.

#include <deal.II/base/function.h>

#include <deal.II/distributed/tria.h>

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <perideal/abc/ebf_diffusion_abc.h>
#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/base/exceptions.h>
#include <perideal/fem/fem_diffusion.h>
#include <perideal/fem/fem_wave.h>

#include "../check.h"
#include "../wave_settings.h"

#include <cmath>
#include <complex>
#include <cstdlib>
#include <ctime>
#include <sstream>
#include <algorithm>
#include <array>
#include <functional>
#include <iomanip>
#include <map>
#include <memory>

using namespace dealii;
using namespace PeriDEAL;
using namespace PeriDEALTests;

namespace
{
  /** Heat kernel of C0 = exp(-4 |x|^2), D = 1 (2D). */
  class HeatKernel : public Function<2>
  {
  public:
    double
    value(const Point<2> &p, const unsigned int = 0) const override
    {
      const double s = 1. + 16. * this->get_time();
      return std::exp(-4. * p.square() / s) / s;
    }
  };

  /** Pulse exp(-log 2 |x|^2 / w2) (half width sqrt(w2)). */
  double
  pulse_of_width(const Point<2> &p, const double w2)
  {
    return std::exp(-std::log(2.) * p.square() / w2);
  }

  /** Pulse of E13: exp(-log 2 |x|^2 / 9). */
  double
  pulse(const Point<2> &p)
  {
    return pulse_of_width(p, 9.);
  }

  using MeshMaker = std::function<void(Triangulation<2> &)>;

  /** Max over DoFs of |a - b| (same support points required) and max |b|. */
  std::pair<double, double>
  compare_fields(const std::vector<std::pair<Point<2>, double>> &a,
                 const std::vector<std::pair<Point<2>, double>> &b)
  {
    check(a.size() == b.size(), "same number of DoFs on 1 and 2 ranks: " + std::to_string(a.size()));
    double diff = 0., scale = 0.;
    for (unsigned int i = 0; i < std::min(a.size(), b.size()); ++i)
      {
        if (a[i].first.distance(b[i].first) > 1e-9)
          diff = std::numeric_limits<double>::infinity();
        diff  = std::max(diff, std::abs(a[i].second - b[i].second));
        scale = std::max(scale, std::abs(b[i].second));
      }
    return {diff, scale};
  }

  /** Number (over all ranks) of absorbing DoFs whose cloud has a DoF owned by another rank. */
  template <typename Abc>
  unsigned int
  straddling_clouds(const Abc &abc, const unsigned int n_owned, const MPI_Comm comm)
  {
    unsigned int n = 0;
    for (unsigned int a = 0; a < abc.absorbing_points().size(); ++a)
      {
        bool ghost = false;
        for (const auto &entry : abc.cloud(a))
          {
            if constexpr (std::is_same_v<std::decay_t<decltype(entry)>, unsigned int>)
              ghost = ghost || entry >= n_owned;
            else
              ghost = ghost || entry.first >= n_owned;
          }
        n += ghost ? 1 : 0;
      }
    return Utilities::MPI::sum(n, comm);
  }

  // ------------------------------------------------------------------------
  // 1 vs 2 ranks. Each rank also runs the case serially (plain
  // Triangulation, MPI_COMM_SELF): the distributed result must agree DoF by
  // DoF to round-off (the clouds, the modes and the pseudo-inverses see the
  // same points; only summation orders differ).

  void
  diffusion_case(const std::string &name, const MeshMaker &mesh, const Fem::FemDiffusionParameters &fp,
                 const double cloud_radius, const unsigned int n_steps, const std::string &imposed = "value",
                 const std::string &fit = "least squares", const double curvature = 0.,
                 const double curvature_radius = 0., const bool curvature_from_mesh = false)
  {
    Abc::EbfParameters ap;
    ap.cloud_radius       = cloud_radius;
    ap.imposed            = imposed;
    ap.fit                = fit;
    ap.boundary_curvature = curvature;
    ap.curvature_radius   = curvature_radius;
    ap.curvature_from_mesh = curvature_from_mesh;
    HeatKernel                                c0;
    parallel::distributed::Triangulation<2> ptria(MPI_COMM_WORLD);
    Triangulation<2>                          stria;
    mesh(ptria);
    mesh(stria);
    Fem::FemDiffusion<2> par(ptria, fp), ser(stria, fp);
    par.setup(Abc::TruncationBoundary::absorbing, ap, c0);
    ser.setup(Abc::TruncationBoundary::absorbing, ap, c0);
    const unsigned int n_straddle =
      straddling_clouds(par.absorbing_boundary(), par.layout().n_owned(), MPI_COMM_WORLD);
    BoundingBox<2> all(std::make_pair(Point<2>(-100., -100.), Point<2>(100., 100.)));
    double         energy_diff = 0.;
    for (unsigned int s = 0; s < n_steps; ++s)
      {
        par.advance();
        ser.advance();
        if (s % 10 == 9)
          energy_diff = std::max(energy_diff, std::abs(par.energy(all) - ser.energy(all)) / ser.energy(all));
      }
    const auto [diff, scale] =
      compare_fields(Fem::gather_by_point(par.layout(), par.solution()),
                     Fem::gather_by_point(ser.layout(), ser.solution()));
    if (root())
      std::cout << "  " << name << ": " << Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) << " ranks, "
                << par.absorbing_boundary().statistics().n_absorbing << " absorbing DoFs, " << n_straddle
                << " clouds straddle ranks; max |C_par - C_serial| " << sci(diff) << " (max |C| " << sci(scale)
                << "), energy rel. diff " << sci(energy_diff) << ", blended clouds "
                << par.absorbing_boundary().statistics().n_blended << " (serial "
                << ser.absorbing_boundary().statistics().n_blended << ")" << std::endl;
    check(par.absorbing_boundary().statistics().n_blended == ser.absorbing_boundary().statistics().n_blended,
          name + ": the same number of clouds blended as serially");
    if (Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) > 1 && imposed != "half derivative")
      check(n_straddle > 0, name + ": some clouds straddle the rank boundary (" + std::to_string(n_straddle) + ")");
    // Round-off: a few hundred steps of 1e-16 perturbations of a stable map.
    check(diff <= 1e-12 * scale, name + ": distributed = serial DoF by DoF, max diff " + sci(diff));
    check(energy_diff <= 1e-12, name + ": energies agree, rel. diff " + sci(energy_diff));
  }

  void
  wave_case(const std::string &name, const MeshMaker &mesh, const Fem::FemWaveParameters &fp,
            const Fem::WaveBoundary boundary, const Abc::WaveAbcParameters &ap, const unsigned int n_steps)
  {
    const ScalarFunctionFromFunctionObject<2> u0(pulse);
    parallel::distributed::Triangulation<2> ptria(MPI_COMM_WORLD);
    Triangulation<2>                          stria;
    mesh(ptria);
    mesh(stria);
    Fem::FemWave<2> par(ptria, fp, boundary, ap, u0), ser(stria, fp, boundary, ap, u0);
    const unsigned int n_straddle =
      boundary == Fem::WaveBoundary::absorbing ?
        straddling_clouds(par.absorbing_boundary(), par.layout().n_owned(), MPI_COMM_WORLD) :
        0;
    const auto all         = [](const Point<2> &) { return true; };
    double     energy_diff = 0.;
    for (unsigned int s = 0; s < n_steps; ++s)
      {
        par.advance();
        ser.advance();
        if (s % 20 == 19)
          energy_diff = std::max(energy_diff, std::abs(par.energy(all) - ser.energy(all)) / ser.energy(all));
      }
    const auto [diff, scale] =
      compare_fields(Fem::gather_by_point(par.layout(), par.solution()),
                     Fem::gather_by_point(ser.layout(), ser.solution()));
    const Point<2> probe(1.3, 0.7);
    const double   probe_diff = std::abs(par.value_at(probe) - ser.value_at(probe));
    if (root())
      std::cout << "  " << name << ": " << Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) << " ranks, "
                << n_straddle << " clouds straddle ranks; max |u_par - u_serial| " << sci(diff) << " (max |u| "
                << sci(scale) << "), energy rel. diff " << sci(energy_diff) << ", probe diff " << sci(probe_diff)
                << std::endl;
    // (On the disk the inward cones of the partition happen not to cross.)
    if (Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) > 1 && boundary == Fem::WaveBoundary::absorbing &&
        name.find("square") != std::string::npos)
      check(n_straddle > 0, name + ": some clouds straddle the rank boundary (" + std::to_string(n_straddle) + ")");
    // The wave updating vectors are pseudo-inverses of moment matrices with
    // condition numbers up to ~1e11 whose columns follow the global DoF ids,
    // which differ between the serial and the distributed numbering: the
    // permuted SVDs differ by eps * cond, measured 1e-11 relative in u after
    // 300 steps (the first-order and diffusion runs, without pseudo-inverse
    // in the step, agree to 1e-14).
    const double tol = boundary == Fem::WaveBoundary::absorbing ? 1e-9 : 1e-12;
    check(diff <= tol * scale, name + ": distributed = serial DoF by DoF, max diff " + sci(diff));
    check(energy_diff <= tol, name + ": energies agree, rel. diff " + sci(energy_diff));
    check(probe_diff <= tol * scale, name + ": point value agrees, diff " + sci(probe_diff));
  }

  MeshMaker
  square(const double L, const unsigned int cells)
  {
    return [=](Triangulation<2> &t) { GridGenerator::subdivided_hyper_cube(t, cells, -L, L); };
  }

  MeshMaker
  disk(const double R, const unsigned int refinements)
  {
    return [=](Triangulation<2> &t) {
      GridGenerator::hyper_ball(t, Point<2>(), R);
      t.refine_global(refinements);
    };
  }

  /**
   * Disk of radius R_out whose inner part is disk(R, refinements) vertex
   * for vertex (session 18): the refined hyper_ball, flattened, merged with
   * a ring mesh on its boundary vertices (the same angles on every ring,
   * rings dr apart, dr adjusted so that R_out is a ring). With MappingQ1
   * the reference then has the near field's cells, mass and stiffness rows
   * inside r < R, so no interpolation or mesh difference enters a
   * near-field vs reference comparison.
   */
  MeshMaker
  disk_nested(const double R, const unsigned int refinements, const double R_out, const double dr)
  {
    return [=](Triangulation<2> &t) {
      Triangulation<2> ball, flat, shell;
      GridGenerator::hyper_ball(ball, Point<2>(), R);
      ball.refine_global(refinements);
      GridGenerator::flatten_triangulation(ball, flat);
      std::map<unsigned int, Point<2>> on_boundary;
      for (const auto &cell : flat.active_cell_iterators())
        for (const unsigned int f : cell->face_indices())
          if (cell->face(f)->at_boundary())
            for (const unsigned int v : cell->face(f)->vertex_indices())
              on_boundary[cell->face(f)->vertex_index(v)] = cell->face(f)->vertex(v);
      std::vector<Point<2>> ring;
      for (const auto &iv : on_boundary)
        ring.push_back(iv.second);
      std::sort(ring.begin(), ring.end(), [](const Point<2> &a, const Point<2> &b) {
        return std::atan2(a[1], a[0]) < std::atan2(b[1], b[0]);
      });
      const unsigned int    n = ring.size(), n_rings = static_cast<unsigned int>(std::ceil((R_out - R) / dr - 1e-9));
      std::vector<Point<2>> vertices;
      for (unsigned int k = 0; k <= n_rings; ++k)
        for (const Point<2> &p : ring)
          vertices.push_back(k == 0 ? p : Point<2>(p * ((R + k * (R_out - R) / n_rings) / p.norm())));
      std::vector<CellData<2>> cells;
      for (unsigned int k = 0; k < n_rings; ++k)
        for (unsigned int j = 0; j < n; ++j)
          {
            // Local x radial, y along the angle: right-handed.
            CellData<2> c;
            c.vertices[0] = k * n + j;
            c.vertices[1] = (k + 1) * n + j;
            c.vertices[2] = k * n + (j + 1) % n;
            c.vertices[3] = (k + 1) * n + (j + 1) % n;
            cells.push_back(c);
          }
      shell.create_triangulation(vertices, cells, SubCellData());
      GridGenerator::merge_triangulations(flat, shell, t, 1e-9);
      check(t.n_vertices() == flat.n_vertices() + n * n_rings && t.n_active_cells() == flat.n_active_cells() + n * n_rings,
            "nested disk: the near field's boundary vertices are shared with the ring mesh");
    };
  }

  void
  rank_invariance_diffusion()
  {
    Fem::FemDiffusionParameters fp;
    fp.time_step = 2e-3;
    diffusion_case("square Q1 lumped forward Euler", square(2., 32), fp, 0.25, 200);
    // Measured: with dt = 1e-2 (D dt / h^2 = 0.64) the 2D EBF + backward
    // Euler run diverges within 50 steps (Q1 and Q2, lumped or consistent);
    // dt = 2e-3 and 5e-3 do not. The setup now rejects it
    // (fem_abc.backward_euler_guard).
    fp.degree      = 2;
    fp.lumped_mass = false;
    fp.scheme      = "backward Euler";
    fp.time_step   = 2e-3;
    diffusion_case("square Q2 consistent backward Euler", square(2., 16), fp, 0.25, 100);
    fp.degree      = 1;
    fp.lumped_mass = true;
    fp.scheme      = "forward Euler";
    fp.time_step   = 1e-3;
    diffusion_case("disk Q1 lumped forward Euler", disk(2., 4), fp, 0.3, 200);
    // Session 10: the EBF normal derivative as the boundary flux, and the
    // stabilized blend (its rounds decide on all ranks alike).
    diffusion_case("disk Q1 lumped forward Euler, normal derivative", disk(2., 4), fp, 0.3, 200,
                   "normal derivative", "monotone");
    diffusion_case("disk Q1 lumped forward Euler, normal derivative stabilized", disk(2., 4), fp, 0.3, 200,
                   "normal derivative", "stabilized");
    // Session 12: the half-derivative flux (per boundary DoF, no clouds).
    diffusion_case("disk Q1 lumped forward Euler, half derivative", disk(2., 4), fp, 0.3, 200, "half derivative",
                   "least squares", 0.5);
    // Session 13: the sub-stochastic (sink) value fit of curved modes
    // about x_i - R n (NNLS per cloud; the clouds straddle the ranks).
    diffusion_case("disk Q1 lumped forward Euler, sink fit, curved modes", disk(2., 4), fp, 0.3, 200, "value", "sink",
                   0., 2.);
    // The half derivative with the curvature estimated from the mesh (the
    // adjacent faces of an owned DoF are owned or ghost cells).
    diffusion_case("disk Q1 lumped forward Euler, half derivative, curvature from the mesh", disk(2., 4), fp, 0.3,
                   200, "half derivative", "least squares", 0., 0., true);
  }

  Abc::WaveAbcParameters
  e13_abc(const std::string &dispersion)
  {
    Abc::WaveAbcParameters ap;
    ap.wave_number_range = 1.;
    ap.cone_angle        = 0.5;
    ap.direction_range   = M_PI / 8.;
    ap.dispersion        = dispersion;
    return ap;
  }

  void
  rank_invariance_wave()
  {
    Fem::FemWaveParameters fp;
    fp.damping   = 0.0125;
    fp.time_step = 0.02;
    wave_case("square Q1 lumped Verlet EBF", square(4., 16), fp, Fem::WaveBoundary::absorbing, e13_abc("discrete"),
              300);
    wave_case("square Q1 lumped Verlet first-order", square(4., 16), fp, Fem::WaveBoundary::first_order,
              e13_abc("discrete"), 300);
    // The tangential viscous layer of session 13 (ring depths and the ring
    // Laplacian across the partition).
    fp.layer_viscosity = 0.2;
    wave_case("square Q1 lumped Verlet EBF, tangential layer", square(4., 16), fp, Fem::WaveBoundary::absorbing,
              e13_abc("discrete"), 300);
    fp.layer_viscosity = 0.;
    fp.scheme      = "Newmark";
    fp.lumped_mass = false;
    wave_case("square Q1 consistent Newmark EBF", square(4., 16), fp, Fem::WaveBoundary::absorbing, e13_abc("local"),
              300);
    fp.scheme      = "velocity Verlet";
    fp.lumped_mass = true;
    wave_case("disk Q1 lumped Verlet EBF", disk(4., 4), fp, Fem::WaveBoundary::absorbing, e13_abc("local"), 300);
    Abc::WaveAbcParameters curved = e13_abc("local");
    curved.curvature_radius       = 4.;
    curved.n_directions           = 0;
    wave_case("disk Q1 lumped Verlet EBF, curved modes", disk(4., 4), fp, Fem::WaveBoundary::absorbing, curved, 300);
    // Session 19: clouds of a fixed size (the ghost layer of the search
    // radius 2 n h, the nearest-point order by global id across ranks).
    curved.cloud_size = 2;
    wave_case("disk Q1 lumped Verlet EBF, curved modes, cloud size 2", disk(4., 4), fp, Fem::WaveBoundary::absorbing,
              curved, 300);
  }

  // ------------------------------------------------------------------------
  // Disk near fields: the absorbing boundary on the curved outer boundary of
  // GridGenerator::hyper_ball, local frames from the outward (radial) normal.

  /**
   * Diffusion of C0 = exp(-4 |x|^2) in the disk of radius 3 to t = 3 against
   * the heat kernel: energy Pi(t) = pi / (8 s) (1 - exp(-8 R^2 / s)),
   * s = 1 + 16 t (closed form over the disk) and the max pointwise error;
   * the same disk with Neumann truncation as the baseline.
   */
  /**
   * Energy errors (max over the run, at t_end; Neumann at t_end), the
   * max pointwise error at t_end of the disk run of disk_diffusion() with
   * @p ap (d_inf = 0.2 set here) and the Delta k used.
   */
  std::array<double, 5>
  run_disk_diffusion(Abc::EbfParameters ap)
  {
    const double       R = 3., t_end = 3.;
    Fem::FemDiffusionParameters fp;
    fp.time_step = 5e-4;
    // Boundary DoF spacing 2 pi R / 128 = 0.147. Measured: d_inf = 0.25 and
    // 0.3 violate the |V| guard at the ball's coarse corners; the monotone
    // fit is stable there but only 1.3-1.5x better than Neumann.
    ap.cloud_radius = 0.2;
    HeatKernel         c0;
    Triangulation<2>   tria;
    disk(R, 5)(tria);
    Fem::FemDiffusion<2> ebf(tria, fp), neumann(tria, fp);
    ebf.setup(Abc::TruncationBoundary::absorbing, ap, c0);
    neumann.setup(Abc::TruncationBoundary::neumann, ap, c0);
    const auto &st = ebf.absorbing_boundary().statistics();
    if (root())
      std::cout << "  disk, Imposed = " << ap.imposed << ": " << st.n_absorbing << " absorbing DoFs, clouds "
                << st.min_cloud_size << ".." << st.max_cloud_size << ", cond " << sci(st.max_condition_number)
                << ", max |V| " << sci(st.max_update_norm) << std::endl;
    const BoundingBox<2> all(std::make_pair(Point<2>(-R, -R), Point<2>(R, R)));
    const auto exact_energy = [R](const double t) {
      const double s = 1. + 16. * t;
      return M_PI / (8. * s) * (1. - std::exp(-8. * R * R / s));
    };
    const double       e0 = exact_energy(0.);
    double             max_ebf = 0., max_neumann = 0., end_ebf = 0., end_neumann = 0.;
    const unsigned int n_steps = static_cast<unsigned int>(std::round(t_end / fp.time_step));
    for (unsigned int s = 1; s <= n_steps; ++s)
      {
        ebf.advance();
        neumann.advance();
        if (s % 100 == 0)
          {
            const double ee = exact_energy(ebf.time());
            end_ebf         = std::abs(ebf.energy(all) - ee) / e0;
            end_neumann     = std::abs(neumann.energy(all) - ee) / e0;
            max_ebf         = std::max(max_ebf, end_ebf);
            max_neumann     = std::max(max_neumann, end_neumann);
          }
      }
    HeatKernel   exact;
    const double err_ebf = ebf.max_error(exact, all), err_neumann = neumann.max_error(exact, all);
    if (root())
      std::cout << "  disk R = 3, t = 3: |Pi - Pi_exact|/Pi0 EBF max " << sci(max_ebf) << " end " << sci(end_ebf)
                << ", Neumann end " << sci(end_neumann) << " (ratio " << end_neumann / end_ebf
                << "); max |C - heat kernel| EBF " << sci(err_ebf) << " Neumann " << sci(err_neumann) << std::endl;
    return {{max_ebf, end_ebf, end_neumann, err_ebf, st.wave_number_range}};
  }

  /**
   * Diffusion of C0 = exp(-4 |x|^2) in the disk of radius 3 to t = 3 against
   * the heat kernel: energy Pi(t) = pi / (8 s) (1 - exp(-8 R^2 / s)),
   * s = 1 + 16 t (closed form over the disk) and the max pointwise error;
   * the same disk with Neumann truncation as the baseline.
   */
  /**
   * Session 14: the sum-of-exponentials history of Imposed = half
   * derivative against the exact O(n) sum on the disk run of
   * disk_diffusion (R = 3, t = 3: 6000 steps, curvature 1/R). Per step
   * the two histories differ by at most accuracy max |C| (the weights'
   * relative accuracy, sum_{j >= 1} |g_j| = 1), which enters the boundary
   * value with the factor w sqrt(dt/D) / (1 + w sqrt(dt/D) + ...) < 1; so
   * over n steps of the non-amplifying map the boundary values differ by
   * at most n accuracy max |C^0|. Asserted: that bound, an energy
   * difference below 1e-3 times the ABC's own energy error against the
   * heat kernel, and the ratio to Neumann of disk_diffusion (>= 10x, end
   * < 2.1e-4) with the fast history. A loose accuracy (1e-4) moves the
   * values more than the default 1e-10 (the comparison sees the history).
   */
  void
  half_derivative_history()
  {
    const double                R = 3., dt = 5e-4;
    const unsigned int          n_steps = 6000;
    Fem::FemDiffusionParameters fp;
    fp.time_step = dt;
    HeatKernel       c0;
    Triangulation<2> tria;
    disk(R, 5)(tria);
    const auto make = [&](const std::string &history, const double accuracy) {
      Abc::EbfParameters ap;
      ap.imposed                  = "half derivative";
      ap.boundary_curvature       = 1. / R;
      ap.half_derivative_history  = history;
      ap.half_derivative_accuracy = accuracy;
      auto d                      = std::make_unique<Fem::FemDiffusion<2>>(tria, fp);
      d->setup(Abc::TruncationBoundary::absorbing, ap, c0);
      return d;
    };
    const auto exact = make("exact", 0.), fast = make("sum of exponentials", 1e-10),
               loose = make("sum of exponentials", 1e-4);
    Fem::FemDiffusion<2> neumann(tria, fp);
    neumann.setup(Abc::TruncationBoundary::neumann, Abc::EbfParameters(), c0);
    const BoundingBox<2> all(std::make_pair(Point<2>(-R, -R), Point<2>(R, R)));
    const auto           exact_energy = [R](const double t) {
      const double s = 1. + 16. * t;
      return M_PI / (8. * s) * (1. - std::exp(-8. * R * R / s));
    };
    const double e0 = exact_energy(0.), c_max = fast->solution().linfty_norm();
    const auto   boundary_diff = [](const Fem::FemDiffusion<2> &a, const Fem::FemDiffusion<2> &b) {
      double m = 0.;
      for (const unsigned int l : a.layout().boundary)
        m = std::max(m, std::abs(a.solution().local_element(l) - b.solution().local_element(l)));
      return m;
    };
    double diff = 0., diff_loose = 0., energy_diff = 0., abc_error = 0., neumann_error = 0.;
    for (unsigned int s = 1; s <= n_steps; ++s)
      {
        exact->advance();
        fast->advance();
        loose->advance();
        neumann.advance();
        if (s % 100 == 0)
          {
            diff             = std::max(diff, boundary_diff(*fast, *exact));
            diff_loose       = std::max(diff_loose, boundary_diff(*loose, *exact));
            const double pe  = exact_energy(fast->time());
            energy_diff      = std::max(energy_diff, std::abs(fast->energy(all) - exact->energy(all)) / e0);
            abc_error        = std::abs(fast->energy(all) - pe) / e0;
            neumann_error    = std::abs(neumann.energy(all) - pe) / e0;
          }
      }
    Fem::DistributedVector field_diff = fast->solution();
    field_diff -= exact->solution();
    const double bound = n_steps * 1e-10 * c_max;
    std::cout << "  disk R = 3, t = 3, " << fast->layout().boundary.size() << " boundary DoFs, "
              << fast->half_derivative_history().n_exponentials()
              << " exponentials: max |C_soe - C_exact| on the boundary " << sci(diff) << " (bound " << sci(bound)
              << "), over all DoFs at t_end " << sci(field_diff.linfty_norm()) << "; max |Pi_soe - Pi_exact|/Pi0 "
              << sci(energy_diff) << "; ABC error |Pi - Pi_heat|/Pi0 at t_end " << sci(abc_error) << ", Neumann "
              << sci(neumann_error) << " (" << neumann_error / abc_error << "x); accuracy 1e-4: "
              << sci(diff_loose) << std::endl;
    check(diff <= bound, "boundary values: max |C_soe - C_exact| = " + sci(diff) + " <= n accuracy max |C0| = " +
                           sci(bound));
    check(energy_diff <= 1e-3 * abc_error, "energy: max |Pi_soe - Pi_exact|/Pi0 = " + sci(energy_diff) +
                                               " <= 1e-3 x the ABC's error " + sci(abc_error));
    check(neumann_error >= 10. * abc_error && abc_error < 2.1e-4,
          "sum of exponentials: end " + sci(abc_error) + " < 2.1e-4, at least 10x closer than Neumann (" +
            std::to_string(neumann_error / abc_error) + "x)");
    check(diff_loose > 10. * diff && diff_loose <= n_steps * 1e-4 * c_max,
          "accuracy 1e-4 moves the boundary values more (" + sci(diff_loose) + ") and within its bound");
  }

  void
  disk_diffusion()
  {
    const auto r = run_disk_diffusion(Abc::EbfParameters());
    // Measured: energy 2.0e-3 (Neumann 4.0e-2, 20x), max error 2.5e-3
    // (Neumann 1.75e-2; the polygonal disk and h ~ 0.1 set the floor).
    // Tolerances ~50 % above the measured values; the 10x is the issue's.
    check(r[0] < 3e-3, "disk EBF: max |Pi - Pi_exact|/Pi0 = " + sci(r[0]) + " < 3e-3");
    check(r[2] > 10. * r[1], "disk EBF at least 10x closer to the heat-kernel energy than Neumann at t_end");
    check(r[3] < 4e-3, "disk EBF: max |C - heat kernel| = " + sci(r[3]) + " < 4e-3");
    // Session 12: the half-derivative flux with the circle's curvature
    // 1/R. Measured: end 1.4e-4 (284x), max over the run 1.1e-3, max |C -
    // heat kernel| 1.1e-4 (Neumann 1.75e-2); with curvature 0 (the planar
    // relation) 2.0e-3 (19.6x). Tolerances ~50 % above the measured values.
    Abc::EbfParameters half;
    half.imposed            = "half derivative";
    half.boundary_curvature = 1. / 3.;
    const auto h = run_disk_diffusion(half);
    check(h[2] >= 10. * h[1] && h[1] < 2.1e-4,
          "disk, half derivative: end " + sci(h[1]) + " < 2.1e-4, at least 10x closer than Neumann (" +
            std::to_string(h[2] / h[1]) + "x)");
    check(h[0] < 1.7e-3 && h[3] < 1.7e-4, "disk, half derivative: max |Pi - Pi_exact|/Pi0 = " + sci(h[0]) +
                                             " < 1.7e-3, max |C - heat kernel| = " + sci(h[3]) + " < 1.7e-4");
    // Session 13: the same with the curvature estimated per boundary DoF
    // from the mesh (measured: end 1.402e-4, 284x, as with the given 1/R
    // to 4 digits).
    Abc::EbfParameters half_mesh   = half;
    half_mesh.boundary_curvature  = 0.;
    half_mesh.curvature_from_mesh = true;
    const auto hm                 = run_disk_diffusion(half_mesh);
    check(hm[2] >= 10. * hm[1] && hm[1] < 2.1e-4 && hm[0] < 1.7e-3,
          "disk, half derivative with the mesh's curvature: end " + sci(hm[1]) + " < 2.1e-4 (" +
            std::to_string(hm[2] / hm[1]) + "x), max " + sci(hm[0]) + " < 1.7e-3");
    // Session 13: the sink fit (V_j >= 0, sum_j V_j <= 1) of the value
    // form. Its sink follows the mode range, as the normal derivative's q
    // did: end ratio vs Neumann with the curved modes (rho = R, 2D WKB
    // amplitude sqrt(R/r)) at Delta k 3 / 5 / 7 / 10: 31x / 20x / 9.9x /
    // 7.1x; plane modes at Delta k 5 / 10: 56x / 7.8x. The pulse is wide
    // at the boundary here (decay rate 8 r/s = 0.49 at t_end), so the range
    // 2/d_inf over-absorbs. Session 14: the sink fit's default Delta k is
    // 1/d_inf (= 5 here: D Delta k^2 = D/d_inf^2, no mode faster than
    // diffusion across the cloud), chosen on this case and verified on the
    // ball, the cube and disks of other R, t_end, d_inf (design.md,
    // session 14). Asserted with the default: the range 1/d_inf is used,
    // and the curved and the plane sink fit reach the issue's 10x (the old
    // default 2/d_inf fails this: 7.1x / 7.8x); tolerances of the max over
    // the run ~50 % above the measured 1.95e-3 / 1.68e-3.
    for (const double rho : {3., 0.})
      {
        Abc::EbfParameters sink;
        sink.fit               = "sink";
        sink.curvature_radius  = rho;
        const auto f           = run_disk_diffusion(sink);
        const std::string name = rho > 0. ? "disk, sink fit, curved modes" : "disk, sink fit, plane modes";
        check(std::abs(f[4] - 1. / 0.2) < 1e-12, name + ": default Delta k " + std::to_string(f[4]) + " = 1/d_inf");
        check(f[2] >= 10. * f[1] && f[0] < (rho > 0. ? 3e-3 : 2.5e-3),
              name + ": at least 10x closer than Neumann at t_end (" + std::to_string(f[2] / f[1]) +
                "x), max |Pi - Pi_exact|/Pi0 = " + sci(f[0]));
      }
  }

  /** Max energy and probe differences of the EBF and first-order runs on a disk near field. */
  struct DiskWaveResult
  {
    double e_ebf = 0., e_first = 0., p_ebf = 0., p_first = 0.;
    /** Max |u - u_ref| over the near-field vertices at t = T. */
    double f_ebf = 0., f_first = 0.;
    /** Largest |E(t) - E_ref(t)|/E0 over the samples of the second half of the run (EBF). */
    double late_ebf = 0.;
    /** Smallest and largest cloud (points, x_i included) and largest thinning stride of the EBF. */
    unsigned int min_cloud = 0, max_cloud = 0, max_stride = 0;
  };

  /**
   * The compact-pulse disk (R = 8, disk(8, 5), nested reference) with
   * every cloud x_i + 2 points. Measured: energy 1.117e-4 vs first order
   * 3.550e-3 (31.8x), probe 1.253e-3 vs 1.589e-2 (12.7x), field at T
   * 1.763e-3 vs 4.715e-2 (26.7x). The 10x is the issue's. The absolute
   * bounds are ~30 % above the measured values: the run is deterministic,
   * so the margin only covers compilers and BLAS, and it is far below the
   * default clouds' 1.21e-3 / 9.9e-3 / 1.39e-2 on this problem.
   */
  void
  check_compact_disk(const std::string &what, const DiskWaveResult &r)
  {
    check(r.e_ebf < 1.5e-4 && 10. * r.e_ebf < r.e_first,
          what + ": max |E - E_ref|/E0 = " + sci(r.e_ebf) + " < 1.5e-4 and 10x below first order (" +
            sci(r.e_first) + ")");
    check(r.p_ebf < 1.6e-3 && 10. * r.p_ebf < r.p_first,
          what + ": probe " + sci(r.p_ebf) + " < 1.6e-3 and 10x below first order (" + sci(r.p_first) + ")");
    check(r.f_ebf < 2.3e-3 && 10. * r.f_ebf < r.f_first,
          what + ": field at t = T " + sci(r.f_ebf) + " < 2.3e-3 and 10x below first order (" +
            sci(r.f_first) + ")");
  }

  /** Diagnostics of run_disk_wave (exploratory scan only; the defaults are the test's run). */
  struct DiskWaveDiagnostics
  {
    /** Centre of the pulse (the test: the disk's centre). */
    Point<2> centre;
    /** Print the signed energy errors and the largest vertex errors at every sample. */
    bool series = false;
    /** Print the error at t = T by boundary angle and by depth. */
    bool where = false;
    /** Print the clouds of the absorbing DoFs of the first quadrant. */
    bool clouds = false;
  };

  /**
   * The initial data of run_disk_wave (session 18; the defaults are
   * fem_mpi.disk_wave's problem).
   */
  struct DiskWaveProblem
  {
    /** The pulse exp(-log 2 |x - c|^2 / w2). */
    double width2 = 9.;
    /**
     * Zero the reference's initial data outside r = R (the data an ABC can
     * represent: the near field's own data and nothing outside).
     */
    bool truncate_reference = false;
  };

  DiskWaveResult
  run_disk_wave(const MeshMaker &near_mesh, const MeshMaker &far_mesh, const double R, const double T,
                const Abc::WaveAbcParameters &ap, const bool newmark = false,
                const DiskWaveDiagnostics &diag = DiskWaveDiagnostics(),
                const DiskWaveProblem &problem = DiskWaveProblem())
  {
    Fem::FemWaveParameters fp;
    fp.damping   = 0.0125;
    fp.time_step = 0.02;
    if (newmark)
      {
        fp.scheme      = "Newmark";
        fp.lumped_mass = false;
      }
    const Point<2>                            c0 = diag.centre;
    const double                              w2 = problem.width2;
    const ScalarFunctionFromFunctionObject<2> u0(
      [c0, w2](const Point<2> &p) { return pulse_of_width(Point<2>(p - c0), w2); });
    const bool                                cut = problem.truncate_reference;
    const ScalarFunctionFromFunctionObject<2> u0_ref([c0, w2, cut, R](const Point<2> &p) {
      return cut && p.norm() > R * (1. + 1e-9) ? 0. : pulse_of_width(Point<2>(p - c0), w2);
    });
    Triangulation<2>                          near, far;
    near_mesh(near);
    far_mesh(far);
    Fem::FemWave<2> ref(far, fp, Fem::WaveBoundary::dirichlet, ap, u0_ref);
    Fem::FemWave<2> first(near, fp, Fem::WaveBoundary::first_order, ap, u0);
    Fem::FemWave<2> ebf(near, fp, Fem::WaveBoundary::absorbing, ap, u0);
    const auto     &st = ebf.absorbing_boundary().statistics();
    if (root())
      std::cout << "  disk: " << st.n_absorbing << " absorbing DoFs, clouds " << st.min_cloud_size << ".."
                << st.max_cloud_size << " stride " << st.max_stride << ", cond " << sci(st.max_condition_number)
                << ", max|V| " << sci(st.max_update_norm) << std::endl;
    if (diag.clouds && root())
      {
        // Per absorbing DoF in the first quadrant: angle, cloud (x_i first)
        // as (depth along -n, tangential offset) pairs, max |V_G|, sum |V_G|.
        const auto &lay  = ebf.layout();
        const auto &abcb = ebf.absorbing_boundary();
        for (unsigned int a = 0; a < abcb.absorbing_points().size(); ++a)
          {
            const Point<2> &x  = lay.points[abcb.absorbing_points()[a]];
            const double    an = std::atan2(x[1], x[0]);
            if (an < -1e-9 || an > M_PI / 2. + 1e-9)
              continue;
            const Tensor<1, 2> n = x / x.norm();
            std::cout << "    angle " << an * 180. / M_PI << ":";
            for (const unsigned int j : abcb.cloud(a))
              {
                const Tensor<1, 2> dx = lay.points[j] - x;
                std::cout << " (" << -(dx * n) << ", " << dx[0] * (-n[1]) + dx[1] * n[0] << ")";
              }
            std::cout << " max|V| " << abcb.cloud_info(a).vmax_g << " sum|V| " << abcb.cloud_info(a).row_sum_g
                      << std::endl;
          }
      }
    const auto inside = [R](const Point<2> &p) { return p.norm() < R - 0.5; };
    DiskWaveResult     r;
    const double       e0      = ref.energy(inside);
    r.min_cloud                = st.min_cloud_size;
    r.max_cloud                = st.max_cloud_size;
    r.max_stride               = st.max_stride;
    const unsigned int n_steps = static_cast<unsigned int>(std::round(T / fp.time_step));
    const Point<2>     probe(0.625 * R, 0.3125 * R);
    for (unsigned int s = 1; s <= n_steps; ++s)
      {
        ref.advance();
        first.advance();
        ebf.advance();
        if (s % (n_steps / 16) == 0)
          {
            const double er = ref.energy(inside);
            r.e_ebf         = std::max(r.e_ebf, std::abs(ebf.energy(inside) - er) / e0);
            r.e_first       = std::max(r.e_first, std::abs(first.energy(inside) - er) / e0);
            const double ur = ref.value_at(probe);
            r.p_ebf         = std::max(r.p_ebf, std::abs(ebf.value_at(probe) - ur));
            r.p_first       = std::max(r.p_first, std::abs(first.value_at(probe) - ur));
            if (2 * s > n_steps)
              r.late_ebf = std::max(r.late_ebf, std::abs(ebf.energy(inside) - er) / e0);
            if (diag.series)
              {
                // Largest vertex errors now, on the boundary and inside.
                double fb_e = 0., fb_f = 0., fi_e = 0., fi_f = 0.;
                for (const auto &cell : near.active_cell_iterators())
                  for (const unsigned int v : cell->vertex_indices())
                    {
                      const Point<2> p  = cell->vertex(v);
                      const double   ur = ref.value_at(p);
                      const bool     bd = p.norm() > R - 1e-6;
                      double        &fe = bd ? fb_e : fi_e, &ff = bd ? fb_f : fi_f;
                      fe                = std::max(fe, std::abs(ebf.value_at(p) - ur));
                      ff                = std::max(ff, std::abs(first.value_at(p) - ur));
                    }
                if (root())
                  std::cout << "    t " << s * fp.time_step << " E_ref/E0 " << sci(er / e0) << " dE EBF "
                            << sci((ebf.energy(inside) - er) / e0) << " first " << sci((first.energy(inside) - er) / e0)
                            << " | field bdry EBF " << sci(fb_e) << " first " << sci(fb_f) << " inside EBF "
                            << sci(fi_e) << " first " << sci(fi_f) << std::endl;
                // Signed values at the centre and at (R, 0): ref, EBF - ref, first - ref.
                for (const Point<2> &q : {Point<2>(), Point<2>(R, 0.), Point<2>(R / std::sqrt(2.), R / std::sqrt(2.))})
                  {
                    const double uq = ref.value_at(q), eq = ebf.value_at(q), fq = first.value_at(q);
                    if (root())
                      std::cout << "      at (" << q << "): ref " << sci(uq) << " EBF-ref " << sci(eq - uq)
                                << " first-ref " << sci(fq - uq) << std::endl;
                  }
              }
          }
      }
    if (diag.where)
      {
        // Max |u - u_ref| at t = T by angle of the boundary vertices (32
        // bins) and by distance from the boundary.
        std::vector<double> ang_e(32, 0.), ang_f(32, 0.), ang_r(32, 0.);
        const std::vector<double> depths{0.05, 0.5, 1., 2., 4., 8.1};
        std::vector<double>       dep_e(depths.size(), 0.), dep_f(depths.size(), 0.), dep_r(depths.size(), 0.);
        for (const auto &cell : near.active_cell_iterators())
          for (const unsigned int v : cell->vertex_indices())
            {
              const Point<2> p  = cell->vertex(v);
              const double   ur = ref.value_at(p), ee = std::abs(ebf.value_at(p) - ur),
                           ef = std::abs(first.value_at(p) - ur);
              const double depth = R - p.norm();
              unsigned int k     = 0;
              while (k + 1 < depths.size() && depth > depths[k])
                ++k;
              dep_e[k] = std::max(dep_e[k], ee);
              dep_f[k] = std::max(dep_f[k], ef);
              dep_r[k] = std::max(dep_r[k], std::abs(ur));
              if (depth < 1e-6)
                {
                  const double       a = std::atan2(p[1], p[0]) + (p[1] < 0. ? 2. * M_PI : 0.);
                  const unsigned int b = std::min(31u, static_cast<unsigned int>(a / (2. * M_PI) * 32.));
                  ang_e[b]             = std::max(ang_e[b], ee);
                  ang_f[b]             = std::max(ang_f[b], ef);
                  ang_r[b]             = std::max(ang_r[b], std::abs(ur));
                }
            }
        if (root())
          {
            std::cout << "  boundary error at T by angle bin (deg start: EBF / first / |ref|):" << std::endl;
            for (unsigned int b = 0; b < 32; ++b)
              std::cout << "    " << b * 11.25 << ": " << sci(ang_e[b]) << " / " << sci(ang_f[b]) << " / "
                        << sci(ang_r[b]) << std::endl;
            std::cout << "  error at T by depth (up to: EBF / first / |ref|):" << std::endl;
            for (unsigned int k = 0; k < depths.size(); ++k)
              std::cout << "    " << depths[k] << ": " << sci(dep_e[k]) << " / " << sci(dep_f[k]) << " / "
                        << sci(dep_r[k]) << std::endl;
          }
      }
    // Field error at t = T over the near-field vertices (the issue's measure).
    for (const auto &cell : near.active_cell_iterators())
      for (const unsigned int v : cell->vertex_indices())
        {
          const Point<2> p  = cell->vertex(v);
          const double   ur = ref.value_at(p);
          r.f_ebf           = std::max(r.f_ebf, std::abs(ebf.value_at(p) - ur));
          r.f_first         = std::max(r.f_first, std::abs(first.value_at(p) - ur));
        }
    if (root())
      std::cout << "  disk R = " << R << ", t = " << T << ": max |E - E_ref|/E0 EBF " << sci(r.e_ebf)
                << " first-order " << sci(r.e_first) << " (ratio " << r.e_first / r.e_ebf << "); probe EBF "
                << sci(r.p_ebf) << " first-order " << sci(r.p_first) << " (ratio " << r.p_first / r.p_ebf
                << "); field at t = T EBF " << sci(r.f_ebf) << " first-order " << sci(r.f_first) << " (ratio "
                << r.f_first / r.f_ebf << ")" << std::endl;
    return r;
  }

  /**
   * Difference of two extended-disk (Dirichlet) runs in the metrics of
   * run_disk_wave (session 18): max over the 16 samples of
   * |E_b - E_a|/E0_a over the cells with centre r < R - 0.5 (each on its
   * own mesh), of |u_b - u_a| at the probe, and max |u_b - u_a| over the
   * vertices of @p near_mesh at T. @p cut_a / @p cut_b: zero initial data
   * outside r = R. This is the floor an ABC comparison against run a has
   * when run b is what the ABC can at best reproduce.
   */
  std::array<double, 3>
  run_disk_floor(const MeshMaker &near_mesh, const MeshMaker &mesh_a, const bool cut_a, const MeshMaker &mesh_b,
                 const bool cut_b, const double R, const double T, const double w2)
  {
    Fem::FemWaveParameters fp;
    fp.damping   = 0.0125;
    fp.time_step = 0.02;
    const auto data = [R, w2](const bool cut) {
      return ScalarFunctionFromFunctionObject<2>(
        [R, w2, cut](const Point<2> &p) { return cut && p.norm() > R * (1. + 1e-9) ? 0. : pulse_of_width(p, w2); });
    };
    const ScalarFunctionFromFunctionObject<2> u0_a = data(cut_a), u0_b = data(cut_b);
    Triangulation<2>                          near, ta, tb;
    near_mesh(near);
    mesh_a(ta);
    mesh_b(tb);
    const Abc::WaveAbcParameters ap;
    Fem::FemWave<2>              a(ta, fp, Fem::WaveBoundary::dirichlet, ap, u0_a);
    Fem::FemWave<2>              b(tb, fp, Fem::WaveBoundary::dirichlet, ap, u0_b);
    const auto                   inside  = [R](const Point<2> &p) { return p.norm() < R - 0.5; };
    const double                 e0      = a.energy(inside);
    const unsigned int           n_steps = static_cast<unsigned int>(std::round(T / fp.time_step));
    const Point<2>               probe(0.625 * R, 0.3125 * R);
    std::array<double, 3>        r{{0., 0., 0.}};
    for (unsigned int s = 1; s <= n_steps; ++s)
      {
        a.advance();
        b.advance();
        if (s % (n_steps / 16) == 0)
          {
            r[0] = std::max(r[0], std::abs(b.energy(inside) - a.energy(inside)) / e0);
            r[1] = std::max(r[1], std::abs(b.value_at(probe) - a.value_at(probe)));
          }
      }
    for (const auto &cell : near.active_cell_iterators())
      for (const unsigned int v : cell->vertex_indices())
        r[2] = std::max(r[2], std::abs(b.value_at(cell->vertex(v)) - a.value_at(cell->vertex(v))));
    if (root())
      std::cout << "  floor: " << ta.n_active_cells() << " vs " << tb.n_active_cells()
                << " cells: max |E_b - E_a|/E0 " << sci(r[0]) << ", probe " << sci(r[1]) << ", field at T "
                << sci(r[2]) << std::endl;
    return r;
  }

  /**
   * The one-step map of the disk(2, 3) near field (the boundary spacing of
   * disk(8, 5)) with the EBF set-up @p ap, Verlet + lumped mass, dt 0.02:
   * radius at most 1 + 1e-10 (round-off above the kept constant eigenvalue
   * 1); with @p three_point_clouds also every cloud x_i + 2 points, stride 1.
   */
  void
  check_small_disk_stable(const Abc::WaveAbcParameters &ap, const std::string &what,
                          const bool three_point_clouds = false)
  {
    Triangulation<2> tria;
    disk(2., 3)(tria);
    Fem::FemWaveParameters fp;
    fp.damping   = 0.0125;
    fp.time_step = 0.02;
    const ScalarFunctionFromFunctionObject<2> u0(pulse);
    Fem::FemWave<2>                           w(tria, fp, Fem::WaveBoundary::absorbing, ap, u0);
    if (three_point_clouds)
      {
        const auto &st = w.absorbing_boundary().statistics();
        check(st.min_cloud_size == 3 && st.max_cloud_size == 3 && st.max_stride == 1,
              what + ": every cloud x_i + 2 points along the normal, stride 1");
      }
    unsigned int n_up = 0;
    const double rho  = w.one_step_spectral_radius(4000, &n_up);
    if (root())
      std::cout << "  " << what << ": one-step spectral radius 1 + " << sci(rho - 1.) << std::endl;
    check(rho <= 1. + 1e-10, what + ": one-step spectral radius " + sci(rho - 1.) + " above 1 <= 1e-10");
  }

  /**
   * E13-type viscous waves in the disk of radius 8 (h ~ 0.4, Q1 lumped,
   * velocity Verlet, local dispersion) against the extended disk of radius
   * 18 (nothing reflected there is back before t = 16) and the first-order
   * ABC on the same disk. EBF with curved modes (Curvature radius = R,
   * normal modes only; session 12).
   */
  void
  disk_wave()
  {
    const double           R = 8., T = 16., R_ref = 0.5 * (T + R + 6.) + 3.;
    Abc::WaveAbcParameters ap = e13_abc("local");
    ap.curvature_radius       = R;
    ap.n_directions           = 0;
    const auto r = run_disk_wave(disk(R, 5), disk(R_ref, 6), R, T, ap);
    // Plane modes (the source, Curvature radius 0) were NOT better than the
    // first-order ABC here: energy 1.36e-2 vs 1.16e-2, probe 0.107 vs
    // 0.043, field at T 0.112 vs 0.084; the default clouds (d_inf = 2 h)
    // have 2-3 points, all behind along the normal. Scans of sessions 6/7
    // and 12 (doc/design.md): d_inf, cone, Delta phi, Delta k, n_k, time
    // levels, pseudo-inverse cutoff, fit form increment: 1.2e-2 .. 1.5e-2 or
    // divergence. The plane modes miss the cylindrical spreading
    // (amplitude ~ r^-1/2) of the low wave numbers (k R ~ 1 .. 8).
    // Measured with the curved modes: energy 5.68e-3 vs 1.16e-2 (2.0x),
    // probe 1.48e-2 vs 4.33e-2 (2.9x), field at t = T 2.08e-2 vs 8.45e-2
    // (4.1x); the issue's 10x is NOT reached, and the gain is lost on the
    // once-refined disk (refinement 6: 1.00e-2 vs 1.18e-2; doc/design.md,
    // session 12). Tolerances ~20 % beyond the measured values.
    // Session 17: this gain is specific to the mesh. d_inf = 2 h leaves 16
    // of the 128 boundary DoFs (within 14 deg of the axes) with clouds of
    // x_i + 1 point, the others x_i + 2; with either size everywhere the
    // EBF is at the first-order level (1.07x / 0.95x in energy), the two
    // kinds err with opposite signs and the mixture partly cancels
    // (doc/design.md, session 17).
    check(r.e_first < 1.4e-2, "disk first-order ABC: max |E - E_ref|/E0 = " + sci(r.e_first) + " < 1.4e-2");
    check(r.e_ebf < 7e-3 && 1.7 * r.e_ebf < r.e_first,
          "disk EBF, curved modes: max |E - E_ref|/E0 = " + sci(r.e_ebf) + " < 7e-3 and 1.7x below first order");
    check(3.3 * r.f_ebf < r.f_first && 2.4 * r.p_ebf < r.p_first,
          "disk EBF, curved modes: field at t = T " + sci(r.f_ebf) + " 3.3x and probe " + sci(r.p_ebf) +
            " 2.4x below first order (" + sci(r.f_first) + ", " + sci(r.p_first) + ")");
    // Stability: the one-step map on disk(2, 3) (the same boundary spacing)
    // has radius 1 (the kept constant; measured 1 + 0, disk(4, 4) 1 + 5e-14).
    Abc::WaveAbcParameters small = ap;
    small.curvature_radius       = 2.;
    check_small_disk_stable(small, "disk EBF, curved modes");
  }

  /**
   * Session 18: the disk comparison of disk_wave made well posed (issue 4).
   * disk_wave's pulse (half width 3) is still 7.2e-3 at r = R = 8, with zero
   * velocity. The reference has the part outside R too, and half of that
   * travels inward. The near field does not have it, so no ABC can
   * reproduce it. Measured (design.md, session 18): that floor alone is
   * 1.96e-3 in energy against the first-order ABC's 1.16e-2, i.e. above
   * the 1.16e-3 a 10x needs, and the non-nested reference hyper_ball adds
   * 3.7e-3 (its cells with centre r < 7.5 are not the near field's). Here
   * the pulse has half width sqrt(3.2) (u0(R) = 1e-6, tail floor 1.6e-8 in
   * energy), the reference is disk_nested (the near field's cells inside
   * R; rings 0.2 apart to R_ref, dr / 2: 2.6e-5 in energy), and every
   * cloud is x_i + 2 points along the normal (d_inf = 0.4137 = 2.05 h; the
   * default 2 h mixes x_i + 1 and x_i + 2, session 17).
   */
  void
  disk_wave_compact()
  {
    const double           R = 8., T = 16., R_ref = 0.5 * (T + R + 6.) + 3.;
    Abc::WaveAbcParameters ap = e13_abc("local");
    ap.curvature_radius       = R;
    ap.n_directions           = 0;
    ap.cloud_radius           = 0.4137;
    DiskWaveProblem problem;
    problem.width2 = 3.2;
    // The data an ABC cannot represent: u0 at the boundary, ~1e-6.
    check(pulse_of_width(Point<2>(R, 0.), problem.width2) < 1.1e-6, "compact pulse: u0(R) < 1.1e-6");
    const auto r = run_disk_wave(disk(R, 5), disk_nested(R, 5, R_ref, 0.2), R, T, ap, false, DiskWaveDiagnostics(),
                                 problem);
    // The premise: x_i + 2 points in every cloud, none thinned.
    check(r.min_cloud == 3 && r.max_cloud == 3 && r.max_stride == 1,
          "compact disk: every cloud x_i + 2 points along the normal, stride 1");
    check_compact_disk("compact disk EBF", r);
    // The diagnosis, guarded: on disk_wave's problem (half width 3, the
    // hyper_ball reference) the reference with its data zeroed outside R
    // (what an ideal ABC reproduces) differs from the full reference by
    // 1.96e-3 in energy (measured), more than disk_wave's first-order bound
    // 1.4e-2 / 10, so no ABC can show 10x there in energy. Bound: that
    // 1.4e-3, 30 % below the measured value.
    const auto floor = run_disk_floor(disk(R, 5), disk(R_ref, 6), false, disk(R_ref, 6), true, R, T, 9.);
    check(floor[0] > 1.4e-3, "disk_wave's problem: the tail outside R alone moves the energy by " + sci(floor[0]) +
                               " > 1.4e-3 (disk_wave's first-order bound / 10)");
    // Stability: the one-step map on disk(2, 3) (the same boundary spacing)
    // with clouds of the same kind (d_inf 0.40 there gives x_i + 2 in every
    // cloud; 0.4137 thins some to x_i + 1 at stride 2: 1 + 4.4e-4). Measured
    // 1 + 1.2e-14 (0 eigenvalues above 1 + 1e-8); disk(4, 4), rho 4, d_inf
    // 0.4137 (every cloud x_i + 2): 1 + 0 (design.md, session 18).
    Abc::WaveAbcParameters small = ap;
    small.curvature_radius       = 2.;
    small.cloud_radius           = 0.40;
    check_small_disk_stable(small, "disk(2, 3), x_i + 2 clouds", true);
  }

  /**
   * Session 19 (issue 4): disk_wave_compact's problem with the cloud
   * composition set by Absorbing boundary/Cloud size = 2 (x_i and its 2
   * nearest cone points; the cloud radius left at its default, which is
   * then the search radius 4 h) instead of the hand-tuned d_inf = 2.05 h.
   * The default d_inf = 2 h gives 16 of the 128 clouds x_i + 1 point and
   * only 2.9x / 1.6x / 3.4x here (design.md, session 18); the cloud size
   * gives every cloud x_i + 2 points along the normal on this mesh, on the
   * refined disk and on disk(2, 3) with the same option value (d_inf had to
   * be 0.4137 here and 0.40 there).
   */
  void
  disk_wave_cloud_size()
  {
    const double           R = 8., T = 16., R_ref = 0.5 * (T + R + 6.) + 3.;
    Abc::WaveAbcParameters ap = e13_abc("local");
    ap.curvature_radius       = R;
    ap.n_directions           = 0;
    ap.cloud_size             = 2;
    DiskWaveProblem problem;
    problem.width2 = 3.2;
    const auto r = run_disk_wave(disk(R, 5), disk_nested(R, 5, R_ref, 0.2), R, T, ap, false, DiskWaveDiagnostics(),
                                 problem);
    check(r.min_cloud == 3 && r.max_cloud == 3 && r.max_stride == 1,
          "cloud size 2: every cloud x_i + 2 points, stride 1");
    // The clouds (and numbers) of d_inf = 0.4137 in disk_wave_compact.
    check_compact_disk("cloud size 2", r);
    // Stability with the same option value on disk(2, 3) (the same
    // boundary spacing; every cloud x_i + 2): measured 1 + 1.2e-14.
    Abc::WaveAbcParameters small = ap;
    small.curvature_radius       = 2.;
    check_small_disk_stable(small, "disk(2, 3), cloud size 2", true);
  }

  // Exploratory (not registered): FEM_DISK_SCAN="key=value ...; ..." runs
  // of disk_wave with the EBF keys of with_wave_settings (on e13_abc
  // ("local")), plus R, T, ref (refinements of the reference disk),
  // session 18: nested=1 (reference disk_nested, rings dr apart (dr, 0.2),
  // grow: R_ref larger by that), w2 (pulse exp(-log 2 |x|^2 / w2)), cut=1
  // (the reference's data zero outside R), floor=A,B (run_disk_floor; see
  // below), decay=T1 (EBF energy to T1), ranks=N (1 vs N ranks, mpirun),
  // newmark=1, level (near refinement at R = 8), cloudh (d_inf / h),
  // x0, y0 (pulse centre; diagnostic), series=1 (signed energy errors and
  // max vertex errors, boundary / inside, at every sample), where=1 (error
  // at T by boundary angle and by depth), clouds=1 (the clouds of the
  // first quadrant), csize (Cloud size, session 19), and
  // rho=R0 (one-step spectral radius on disk(R0, 3 + log2(R0/2)), the
  // boundary spacing of the disk_wave mesh; rholevel: refined more) or
  // rhoonly=1 (no run).
  void
  disk_wave_scan()
  {
    const char        *env = std::getenv("FEM_DISK_SCAN");
    std::istringstream runs(env ? env : "");
    std::string        run;
    while (std::getline(runs, run, ';'))
      {
        const auto kv = key_values(run);
        const auto num = [&](const std::string &k, const double def) { return kv.count(k) ? std::stod(kv.at(k)) : def; };
        Abc::WaveAbcParameters ap = with_wave_settings(e13_abc("local"), kv);
        ap.cloud_size             = static_cast<unsigned int>(num("csize", ap.cloud_size));
        if (root())
          std::cout << "[" << run << "]" << std::endl;
        try
          {
            if (kv.count("rho"))
              {
                const double     R0 = num("rho", 2.);
                Triangulation<2> tria;
                disk(R0, 3 + static_cast<unsigned int>(std::round(std::log2(R0 / 2.))) +
                           static_cast<unsigned int>(num("rholevel", 0)))(tria);
                Fem::FemWaveParameters fp;
                fp.damping   = 0.0125;
                fp.time_step = num("dt", 0.02);
                if (kv.count("newmark"))
                  {
                    fp.scheme      = "Newmark";
                    fp.lumped_mass = false;
                  }
                const ScalarFunctionFromFunctionObject<2> u0(pulse);
                Fem::FemWave<2>      w(tria, fp, Fem::WaveBoundary::absorbing, ap, u0);
                unsigned int         n_up = 0;
                std::complex<double> dom;
                const double         rho = w.one_step_spectral_radius(8000, &n_up, &dom);
                const auto          &st  = w.absorbing_boundary().statistics();
                std::cout << "  rho - 1 = " << sci(rho - 1.) << " (" << n_up << " up, dominant " << dom
                          << "), clouds " << st.min_cloud_size << ".." << st.max_cloud_size << ", max|V| "
                          << sci(st.max_update_norm) << std::endl;
              }
            if (!kv.count("rhoonly"))
              {
                // An off-centre pulse is |c| closer to the reference's edge.
                const double R = num("R", 8.), T = num("T", 16.),
                             R_ref = 0.5 * (T + R + 6.) + 3. + std::hypot(num("x0", 0.), num("y0", 0.));
                // The boundary spacing of disk(8, 5) (0.39) for every R.
                const unsigned int level =
                  static_cast<unsigned int>(num("level", 5)) + static_cast<unsigned int>(std::round(std::log2(R / 8.)));
                if (kv.count("cloudh"))
                  {
                    // d_inf = cloudh * h, h as in FemWave (largest minimum vertex distance).
                    Triangulation<2> t;
                    disk(R, level)(t);
                    double h = 0.;
                    for (const auto &cell : t.active_cell_iterators())
                      h = std::max(h, cell->minimum_vertex_distance());
                    ap.cloud_radius = num("cloudh", 2.) * h * (1. + 1e-9);
                    if (root())
                      std::cout << "  h = " << h << ", d_inf = " << ap.cloud_radius << std::endl;
                  }
                // Session 18: the reference disk nested (nested=1, rings
                // dr apart, out to R_ref + grow), the pulse width (w2), the
                // reference's data zero outside R (cut=1).
                const double dr = num("dr", 0.2), R_big = R_ref + num("grow", 0.);
                const MeshMaker far_mesh =
                  kv.count("nested") ? disk_nested(R, level, R_big, dr) :
                                       disk(R_big, static_cast<unsigned int>(num("ref", level + 1)));
                if (kv.count("floor"))
                  {
                    // floor=A,B: run b against run a; each of std (hyper_ball
                    // R_ref, refinement level + 1), stdcut, nest, nestcut,
                    // nestfine (dr / 2), nestbig (R_ref + 4).
                    const std::string spec = kv.at("floor");
                    const auto        comma = spec.find(',');
                    const auto        named = [&](const std::string &n) {
                      if (n.rfind("std", 0) == 0)
                        return disk(R_ref, level + 1);
                      if (n.rfind("nestfine", 0) == 0)
                        return disk_nested(R, level, R_ref, 0.5 * dr);
                      if (n.rfind("nestbig", 0) == 0)
                        return disk_nested(R, level, R_ref + 4., dr);
                      return disk_nested(R, level, R_ref, dr);
                    };
                    const std::string a = spec.substr(0, comma), b = spec.substr(comma + 1);
                    const auto cut = [](const std::string &n) { return n.find("cut") != std::string::npos; };
                    run_disk_floor(disk(R, level), named(a), cut(a), named(b), cut(b), R, T, num("w2", 9.));
                    continue;
                  }
                if (kv.count("ranks"))
                  {
                    // ranks=N: the EBF on disk(R, level) distributed vs
                    // serial over N steps (run with mpirun -np 2).
                    Fem::FemWaveParameters fp;
                    fp.damping   = 0.0125;
                    fp.time_step = 0.02;
                    wave_case("disk(" + std::to_string(R) + ", " + std::to_string(level) + ") EBF", disk(R, level), fp,
                              Fem::WaveBoundary::absorbing, ap, static_cast<unsigned int>(num("ranks", 300)));
                    continue;
                  }
                if (kv.count("decay"))
                  {
                    // decay=T1: the EBF run alone to t = T1; the energy of the
                    // whole near field every 50 steps, its largest increase
                    // between samples and its value at T1 (relative to E0).
                    Fem::FemWaveParameters fp;
                    fp.damping   = 0.0125;
                    fp.time_step = 0.02;
                    const double                              w2 = num("w2", 9.);
                    const ScalarFunctionFromFunctionObject<2> u0(
                      [w2](const Point<2> &p) { return pulse_of_width(p, w2); });
                    Triangulation<2> tria;
                    disk(R, level)(tria);
                    Fem::FemWave<2>    w(tria, fp, Fem::WaveBoundary::absorbing, ap, u0);
                    const auto         all = [](const Point<2> &) { return true; };
                    const double       e0  = w.energy(all);
                    double             e = e0, up = 0., t_up = 0., up_rel = 0., up_late = 0.;
                    const unsigned int n = static_cast<unsigned int>(std::round(num("decay", 400.) / fp.time_step));
                    for (unsigned int s = 1; s <= n; ++s)
                      {
                        w.advance();
                        if (s % 50 == 0)
                          {
                            const double en = w.energy(all);
                            if ((en - e) / e0 > up)
                              {
                                up   = (en - e) / e0;
                                t_up = s * fp.time_step;
                              }
                            up_rel = std::max(up_rel, (en - e) / e);
                            if (2 * s > n)
                              up_late = std::max(up_late, (en - e) / e0);
                            e = en;
                          }
                      }
                    if (root())
                      std::cout << "  decay to t = " << n * fp.time_step << ": E/E0 " << sci(e / e0)
                                << ", largest increase between samples " << sci(up) << " E0 (at t = " << t_up
                                << "), relative to E(t) " << sci(up_rel) << ", in the second half " << sci(up_late)
                                << " E0" << std::endl;
                    continue;
                  }
                DiskWaveProblem problem;
                problem.width2             = num("w2", 9.);
                problem.truncate_reference = kv.count("cut") > 0;
                DiskWaveDiagnostics diag;
                diag.centre = Point<2>(num("x0", 0.), num("y0", 0.));
                diag.series = kv.count("series") > 0;
                diag.where  = kv.count("where") > 0;
                diag.clouds = kv.count("clouds") > 0;
                const auto r = run_disk_wave(disk(R, level), far_mesh, R, T, ap, kv.count("newmark") > 0, diag, problem);
                if (root())
                  std::cout << "  late energy error EBF " << sci(r.late_ebf) << std::endl;
              }
          }
        catch (std::exception &e)
          {
            std::cout << "  exception: " << e.what() << std::endl;
          }
      }
  }

  /** 3D heat kernel of C0 = exp(-4 |x|^2), D = 1. */
  class HeatKernel3d : public Function<3>
  {
  public:
    double
    value(const Point<3> &p, const unsigned int = 0) const override
    {
      const double s = 1. + 16. * this->get_time();
      return std::exp(-4. * p.square() / s) / std::pow(s, 1.5);
    }
  };

  /**
   * 3D FEM diffusion (Q1 lumped, forward Euler, D = 1) of C0 = exp(-4|x|^2)
   * with the octant-frame EBF ABC (4.24) on a cube (-L, L)^3 or a ball of
   * radius L (GridGenerator::hyper_ball) against the heat kernel: energy
   * Pi(t) = integral of C^2 over the near field in closed form (cube:
   * s^-3 (sqrt(pi s/8) erf(L sqrt(8/s)))^3; ball: 4 pi s^-3 (sqrt(pi)/(4 a^1.5)
   * erf(sqrt(a) L) - L exp(-a L^2)/(2a)), a = 8/s, s = 1 + 16 t) and the max
   * pointwise error; the same mesh with Neumann truncation as the baseline.
   */
  std::array<double, 11>
  diffusion_3d(const bool ball, const double L, const unsigned int refinements, const double t_end,
               const double dt, const double cloud_radius, const std::string &fit = "least squares",
               const std::string &imposed = "value",
               const std::function<void(Abc::EbfParameters &)> &tweak = {}, const bool distributed = false)
  {
    // (distributed: a parallel::distributed mesh over MPI_COMM_WORLD.)
    std::unique_ptr<Triangulation<3>> tria_ptr =
      distributed ? std::make_unique<parallel::distributed::Triangulation<3>>(MPI_COMM_WORLD) :
                    std::make_unique<Triangulation<3>>();
    Triangulation<3> &tria = *tria_ptr;
    if (ball)
      GridGenerator::hyper_ball(tria, Point<3>(), L);
    else
      GridGenerator::hyper_cube(tria, -L, L);
    tria.refine_global(refinements);
    Fem::FemDiffusionParameters fp;
    fp.time_step = dt;
    Abc::EbfParameters ap;
    ap.cloud_radius = cloud_radius;
    ap.fit          = fit;
    ap.imposed      = imposed;
    if (fit == "stabilized")
      {
        // As E11 (PD sphere): the l1 cap 1.5 first; the least-squares
        // vectors it blends exceed the |V| guard.
        ap.max_update_l1   = 1.5;
        ap.max_update_norm = 1e10;
      }
    if (tweak)
      tweak(ap);
    HeatKernel3d         c0;
    Fem::FemDiffusion<3> ebf(tria, fp), neumann(tria, fp);
    const std::clock_t setup_start = std::clock();
    ebf.setup(Abc::TruncationBoundary::absorbing, ap, c0);
    const double setup_cpu = double(std::clock() - setup_start) / CLOCKS_PER_SEC;
    neumann.setup(Abc::TruncationBoundary::neumann, ap, c0);
    const auto &st = ebf.absorbing_boundary().statistics();
    if (root())
      std::cout << "  " << (ball ? "ball" : "cube") << " L = " << L << ": " << ebf.get_dof_handler().n_dofs()
                << " DoFs, " << st.n_absorbing << " absorbing, clouds " << st.min_cloud_size << ".."
                << st.max_cloud_size << ", cond " << sci(st.max_condition_number) << ", max |V| "
                << sci(st.max_update_norm) << ", growth check " << ebf.stability_growth << ", setup "
                << setup_cpu << " s CPU" << std::endl;
    if (fit == "stabilized" && root())
      {
        const auto  &abc   = ebf.absorbing_boundary();
        unsigned int n_one = 0;
        double       sum   = 0.;
        for (unsigned int a = 0; a < abc.absorbing_points().size(); ++a)
          {
            n_one += abc.blend(a) == 1. ? 1 : 0;
            sum += abc.blend(a);
          }
        std::cout << "  stabilized: " << st.n_blended << " clouds blended in " << st.stabilization_rounds
                  << " rounds, " << n_one << " at theta = 1, mean theta " << sum / abc.absorbing_points().size()
                  << ", max sum |V_j| " << st.max_update_l1 << std::endl;
      }
    // Curvature estimated from the mesh (Imposed = half derivative): the
    // range over all boundary DoFs.
    double kappa_min = 0., kappa_max = 0.;
    if (ap.curvature_from_mesh)
      {
        const auto &k = ebf.layout().curvatures;
        kappa_min     = Utilities::MPI::min(k.empty() ? 1e300 : *std::min_element(k.begin(), k.end()), MPI_COMM_WORLD);
        kappa_max     = Utilities::MPI::max(k.empty() ? -1e300 : *std::max_element(k.begin(), k.end()), MPI_COMM_WORLD);
        if (root())
          std::cout << "  curvature from the mesh: " << kappa_min << " .. " << kappa_max << std::endl;
      }
    if (fit == "sink" && root())
      {
        // The sub-stochastic weights: sum_j V_j <= 1 (the sink 1 - sum).
        const auto &abc = ebf.absorbing_boundary();
        double      smin = 1., smax = 0., smean = 0.;
        for (unsigned int a = 0; a < abc.absorbing_points().size(); ++a)
          {
            double sum = 0.;
            for (const auto &jv : abc.cloud(a))
              sum += jv.second;
            smin = std::min(smin, sum);
            smax = std::max(smax, sum);
            smean += sum / abc.absorbing_points().size();
          }
        std::cout << "  sink: sum_j V_j " << smin << " .. " << smax << ", mean " << smean << std::endl;
      }
    if (imposed == "normal derivative" && root())
      {
        // dC/dn = sum_j P_j (C_j - C_i) - q C_i: the sink q and sum_j P_j.
        const auto &abc  = ebf.absorbing_boundary();
        double      qmin = std::numeric_limits<double>::max(), qmax = 0., pmax = 0.;
        for (unsigned int a = 0; a < abc.absorbing_points().size(); ++a)
          {
            double p = 0., v0 = 0.;
            for (const auto &[j, v] : abc.cloud(a))
              (j == abc.absorbing_points()[a] ? v0 : p) += v;
            qmin = std::min(qmin, -(v0 + p));
            qmax = std::max(qmax, -(v0 + p));
            pmax = std::max(pmax, p);
          }
        std::cout << "  normal derivative: sink q " << qmin << " .. " << qmax << ", sum_j P_j <= " << pmax
                  << std::endl;
      }
    const auto exact_energy = [ball, L](const double t) {
      const double s = 1. + 16. * t, a = 8. / s;
      if (ball)
        return 4. * M_PI / (s * s * s) *
               (std::sqrt(M_PI) / (4. * std::pow(a, 1.5)) * std::erf(std::sqrt(a) * L) -
                L * std::exp(-a * L * L) / (2. * a));
      return std::pow(std::sqrt(M_PI / a) * std::erf(L * std::sqrt(a)), 3) / (s * s * s);
    };
    const BoundingBox<3> all(std::make_pair(Point<3>(-L, -L, -L), Point<3>(L, L, L)));
    const double         e0      = exact_energy(0.);
    double               max_ebf = 0., end_ebf = 0., end_neumann = 0.;
    const unsigned int   n_steps = static_cast<unsigned int>(std::round(t_end / dt));
    // Stability in energy: the largest rise of the EBF run's Pi over one step.
    double max_rise = -std::numeric_limits<double>::max(), pi_prev = ebf.energy(all);
    for (unsigned int s = 1; s <= n_steps; ++s)
      {
        ebf.advance();
        neumann.advance();
        const double pi = ebf.energy(all);
        max_rise        = std::max(max_rise, (pi - pi_prev) / e0);
        pi_prev         = pi;
        if (s % (n_steps / 10) == 0 || s == n_steps)
          {
            const double ee = exact_energy(ebf.time());
            end_ebf         = std::abs(ebf.energy(all) - ee) / e0;
            end_neumann     = std::abs(neumann.energy(all) - ee) / e0;
            max_ebf         = std::max(max_ebf, end_ebf);
          }
      }
    HeatKernel3d exact;
    const double err = ebf.max_error(exact, all);
    // Boundary DoFs at t_end where the EBF value lies below the heat kernel
    // (the monotone update cannot fall below its cloud's minimum).
    exact.set_time(ebf.time());
    unsigned int n_below = 0;
    double       min_excess = std::numeric_limits<double>::max();
    for (const unsigned int l : ebf.layout().boundary)
      {
        const double excess = ebf.solution().local_element(l) - exact.value(ebf.layout().points[l]);
        n_below += excess < 0. ? 1 : 0;
        min_excess = std::min(min_excess, excess / exact.value(ebf.layout().points[l]));
      }
    if (root())
      std::cout << "  " << (ball ? "ball" : "cube") << ", t = " << t_end << ": " << n_below << " of "
                << ebf.layout().boundary.size() << " boundary DoFs below the heat kernel, min (C - exact)/exact "
                << sci(min_excess) << std::endl;
    if (root())
      std::cout << "  " << (ball ? "ball" : "cube") << ", t = " << t_end << ": |Pi - Pi_exact|/Pi0 EBF max "
                << sci(max_ebf) << " end " << sci(end_ebf) << ", Neumann end " << sci(end_neumann) << " (ratio "
                << end_neumann / end_ebf << "); max |C - heat kernel| EBF " << sci(err)
                << ", largest one-step rise of Pi/Pi0 " << sci(max_rise) << std::endl;
    // (The half derivative's map has memory: no one-step checks.)
    const double power_growth = imposed == "half derivative" ? 0. : ebf.power_iteration_growth(400);
    if (root())
      std::cout << "  " << (ball ? "ball" : "cube") << ": one-step growth power iteration (400 steps) "
                << power_growth << ", Arnoldi (setup) " << ebf.stability_growth << std::endl;
    return {{max_ebf, end_ebf, end_neumann, err, double(n_below), min_excess, max_rise, power_growth,
             ebf.stability_growth, kappa_min, kappa_max}};
  }

  /**
   * 3D FEM diffusion with the EBF ABC, t = 0.5, dt = 1e-3, d_inf = 0.45:
   * cube (-1.5, 1.5)^3 (16^3 cells, h = 0.1875) and ball of radius 1.5
   * (hyper_ball, 3 refinements). The least-squares fit (4.31) is unusable
   * in 3D here (measured: d_inf = 0.38 grows by 2.4 per step and the guard
   * asks for dt <= 8.8e-6; d_inf = 0.45 / 0.55 violate the |V| guard;
   * the ball's clouds likewise); the monotone fit (V_j >= 0, sum = 1:
   * stable for every cloud with forward Euler) is used. Session 10: the
   * stabilized blend on the ball, and the EBF normal derivative as the
   * boundary flux (Imposed = normal derivative) on both, which reaches the
   * 10x on the ball (doc/design.md, "Session 10: FEM ball ABC").
   */
  void
  diffusion_3d_cube_ball()
  {
    bool rejected = false;
    try
      {
        diffusion_3d(false, 1.5, 4, 0.5, 1e-3, 0.45, "least squares");
      }
    catch (const ParameterError &)
      {
        rejected = true;
      }
    check(rejected, "3D least-squares clouds rejected by the guards (ParameterError)");
    const auto cube = diffusion_3d(false, 1.5, 4, 0.5, 1e-3, 0.45, "monotone");
    // Measured: max 5.3e-3, end 4.1e-3 vs Neumann 4.4e-2 (10.8x), max |C -
    // heat kernel| 1.1e-2 (h = 0.19 sets the floor). Tolerances ~50 % above;
    // the ratio 20 % below the measured one.
    check(cube[0] < 8e-3, "cube: max |Pi - Pi_exact|/Pi0 = " + sci(cube[0]) + " < 8e-3");
    check(cube[2] > 8.5 * cube[1], "cube: EBF at least 8.5x closer to the heat kernel energy than Neumann at t_end");
    check(cube[3] < 1.7e-2, "cube: max |C - heat kernel| = " + sci(cube[3]) + " < 1.7e-2");
    const auto ball = diffusion_3d(true, 1.5, 3, 0.5, 1e-3, 0.45, "monotone");
    // Measured: 2.1e-2 vs Neumann 0.117 (5.4x): the 10x of the issue is NOT
    // reached on the ball with the value form (it is with the normal
    // derivative below). Session 7: not the geometry (heat-kernel energy
    // over the Q1 mesh vs the sphere: 2e-4 Pi0) nor the mesh (the exact
    // heat kernel as boundary values: 2.6e-4 Pi0 at t_end, max error
    // 2.8e-4), but the monotone fit itself: V_j >= 0, sum V_j = 1 makes
    // C_i^{n+1} a convex combination of its cloud, and on a sphere centred
    // at the pulse the boundary is a level set with C rising inward, so
    // C_i cannot decrease, while the heat kernel at r = 1.5 decreases for
    // t > (8 r^2/3 - 1)/16 = 0.31 (the curvature term 2 C_r / r outweighs
    // C_rr); the error grows from t = 0.25 on. On the cube the face
    // neighbours carry smaller values. Signed fits that could extrapolate
    // are unstable here (Arnoldi radius: least squares 1.31, bounded with
    // l1 excess 0.05 1.0033, with modes radial about x_i - R n 1.14 /
    // 1.018); d_inf, Delta k, n_k, n_phi scans (0.45/0.6, 2..8, 5/20,
    // 2..9) give 2.1e-2 .. 4.3e-2, one outlier 5.1e-3 (d_inf 0.6, Delta k 8);
    // adding the time-decaying exact solutions cos(k d.x) exp(-D k^2 t) to
    // the monotone fit makes both worse (cube 1.5e-2, ball 3.1e-2).
    check(ball[0] < 3.2e-2, "ball: max |Pi - Pi_exact|/Pi0 = " + sci(ball[0]) + " < 3.2e-2");
    check(ball[2] > 4. * ball[1], "ball: EBF at least 4x closer than Neumann at t_end (10x not reached)");
    // The mechanism (measured: all 386 boundary values above the heat
    // kernel at t_end, by 29 % or more; on the cube 910 of 1538 below).
    check(ball[4] == 0. && ball[5] > 0.1,
          "ball: every EBF boundary value above the heat kernel at t_end (min excess " + sci(ball[5]) + ")");

    // Session 10: the PD "stabilized" blend (E11: 22.8x), shared through
    // EbfDiffusionAbc::stabilize, with the FEM one-step map. Measured with
    // the l1 cap 1.5 of E11: 5 rounds, all 386 clouds blended, 160 at
    // theta = 1, mean theta 0.955; 1.96e-2 vs 0.117 (5.9x); without the
    // cap 16 rounds, mean theta 0.959, 2.15e-2 (5.4x): stable, but close
    // to the monotone fit, so no better. Asserted: the blend ends stable,
    // not the 10x.
    const auto stab = diffusion_3d(true, 1.5, 3, 0.5, 1e-3, 0.45, "stabilized");
    check(stab[8] > 0. && stab[8] <= 1. + 1e-5 && stab[7] <= 1.,
          "ball, stabilized fit: one-step map stable (Arnoldi " + std::to_string(stab[8]) + ", power iteration " +
            std::to_string(stab[7]) + ")");

    // The EBF normal derivative as the boundary DoF's flux (Imposed =
    // normal derivative, monotone: dC/dn = sum_j P_j (C_j - C_i) - q C_i,
    // P, q >= 0). On the ball NNLS returns P = 0 and q = 1.871 on every
    // cloud, the modes' mean decay rate -k d.n (it depends on Delta k =
    // 2/d_inf, n_k, n_phi, not on the field): a Robin condition, which the
    // convex combination of the value fit could not express (the boundary
    // value falls below its cloud). Measured: end 3.8e-3 vs Neumann 0.117
    // (31x), max over the run 1.47e-2 (at mid-run, where the constant q is
    // below the heat kernel's 8 r / s), every step lowers Pi (largest
    // change -1.4e-4 Pi0), growth 0.99496 (power iteration) / 0.99774
    // (Arnoldi); cube 1.49e-3 vs 4.4e-2 (30x), max 5.1e-3.
    const auto ball_flux = diffusion_3d(true, 1.5, 3, 0.5, 1e-3, 0.45, "monotone", "normal derivative");
    check(ball_flux[2] >= 10. * ball_flux[1], "ball, EBF normal derivative: at least 10x closer than Neumann at t_end (" +
                                                 std::to_string(ball_flux[2] / ball_flux[1]) + "x)");
    check(ball_flux[0] < 2.2e-2, "ball, EBF normal derivative: max |Pi - Pi_exact|/Pi0 = " + sci(ball_flux[0]) +
                                   " < 2.2e-2");
    check(ball_flux[6] <= 0. && ball_flux[7] <= 1. && ball_flux[8] <= 1.,
          "ball, EBF normal derivative: Pi non-increasing every step (largest change " + sci(ball_flux[6]) +
            " Pi0), one-step growth <= 1 (power iteration " + std::to_string(ball_flux[7]) + ", Arnoldi " +
            std::to_string(ball_flux[8]) + ")");
    check(ball_flux[4] > 0., "ball, EBF normal derivative: boundary values below the heat kernel exist (" +
                               std::to_string(int(ball_flux[4])) + " of 386)");
    const auto cube_flux = diffusion_3d(false, 1.5, 4, 0.5, 1e-3, 0.45, "monotone", "normal derivative");
    check(cube_flux[2] >= 10. * cube_flux[1] && cube_flux[0] < 8e-3,
          "cube, EBF normal derivative: at least 10x closer than Neumann at t_end (" +
            std::to_string(cube_flux[2] / cube_flux[1]) + "x), max " + sci(cube_flux[0]) + " < 8e-3");
    check(cube_flux[6] <= 0. && cube_flux[7] <= 1. && cube_flux[8] <= 1.,
          "cube, EBF normal derivative: Pi non-increasing every step, one-step growth <= 1");

    // Session 12: Imposed = half derivative, dC/dn = -(kappa/2) C -
    // D^{-1/2} d^{1/2}C/dt^{1/2} of the boundary DoF's history (kappa: sum
    // of the principal curvatures, 2/R on the sphere; exact for the
    // outgoing 3D monopole). The rate of the Robin sink now follows the
    // field (the normal derivative's q = 1.871 is the modes' mean |k|).
    // Measured: ball end 3.5e-4 vs Neumann 0.117 (330x; the mesh floor with
    // the exact heat kernel as boundary values is 2.6e-4), max over the
    // run 2.6e-3 (early, t <= 0.05), Pi lower after every step; kappa = 0
    // (the planar relation) 8.4e-3 (14x); cube (kappa = 0) 2.1e-3 vs
    // 4.4e-2 (21x), max 5.2e-3. Tolerances ~50 % above the measured
    // errors; the ratio is the issue's 10x.
    const auto half_derivative = [](const double kappa) {
      return [kappa](Abc::EbfParameters &ap) { ap.boundary_curvature = kappa; };
    };
    const auto ball_half =
      diffusion_3d(true, 1.5, 3, 0.5, 1e-3, 0.45, "least squares", "half derivative", half_derivative(2. / 1.5));
    check(ball_half[2] >= 10. * ball_half[1] && ball_half[1] < 5.3e-4,
          "ball, half derivative: end " + sci(ball_half[1]) + " < 5.3e-4, at least 10x closer than Neumann (" +
            std::to_string(ball_half[2] / ball_half[1]) + "x)");
    check(ball_half[0] < 4e-3 && ball_half[6] <= 0.,
          "ball, half derivative: max |Pi - Pi_exact|/Pi0 = " + sci(ball_half[0]) +
            " < 4e-3, Pi non-increasing every step (largest change " + sci(ball_half[6]) + " Pi0)");
    // Session 13: a cloud fit of the value form that reaches the 10x. The
    // sink fit (V_j >= 0, sum_j V_j <= 1: nonnegative least squares
    // without the constant's equality) keeps the max principle of the
    // monotone fit but lets C_i fall below its cloud; with the curved modes
    // about x_i - R n (exact (R/r) exp(k (r - R) + D k^2 t) along n) the
    // fit returns sum_j V_j = 0.9975 .. 0.9982 (mean 0.9977: a sink of
    // ~2.3e-3 per step, 2.3 per unit time). Measured: end 4.43e-3 vs Neumann 0.117 (26x;
    // plane modes 8.2e-3, 14x; monotone 2.1e-2), max over the run = end,
    // max |C - heat kernel| 2.9e-3, Pi lower after every step, growth
    // 0.99688 (power iteration) / 0.99877 (Arnoldi); curvature radius 1.2 /
    // 2 / 3: 32x / 22x / 19x; d_inf 0.6 96x, Delta k 8 23x, dt 5e-4 26x;
    // refinement 4 (d_inf 0.3) 25x (all at Delta k 2/d_inf = 4.44).
    // Session 14: the sink fit's default Delta k is 1/d_inf = 2.22:
    // sum_j V_j 0.99851 .. 0.99870, end 1.61e-3 (72x), max over the run
    // 4.20e-3 (mid-run; 4.43e-3 before), growth 0.99712 / 0.99882. The
    // tolerance on the max stays ~50 % above the session-13 value; the
    // ratio is the issue's 10x.
    const auto ball_sink = diffusion_3d(true, 1.5, 3, 0.5, 1e-3, 0.45, "sink", "value",
                                        [](Abc::EbfParameters &ap) { ap.curvature_radius = 1.5; });
    check(ball_sink[2] >= 10. * ball_sink[1] && ball_sink[0] < 6.6e-3,
          "ball, sink fit with curved modes: at least 10x closer than Neumann at t_end (" +
            std::to_string(ball_sink[2] / ball_sink[1]) + "x), max |Pi - Pi_exact|/Pi0 = " + sci(ball_sink[0]) +
            " < 6.6e-3");
    check(ball_sink[6] <= 0. && ball_sink[7] <= 1. && ball_sink[8] <= 1.,
          "ball, sink fit with curved modes: Pi non-increasing every step (largest change " + sci(ball_sink[6]) +
            " Pi0), one-step growth <= 1 (power iteration " + std::to_string(ball_sink[7]) + ", Arnoldi " +
            std::to_string(ball_sink[8]) + ")");
    // Session 13: kappa estimated per boundary DoF from the mesh
    // (NearFieldLayout::curvatures: (dim - 1) times the mean normal
    // curvature along the chords to the adjacent boundary-face centres).
    // Measured on the ball: 1.321 .. 1.442 (2/R = 1.333; refinement 4:
    // 1.329 .. 1.394), end 3.59e-4 (325x; the given 2/R: 3.54e-4), max
    // over the run 2.6e-3; cube 0 on the faces, up to 12.3 at the edges
    // (rounded on the scale h): 1.8e-3 (24x; kappa 0: 2.1e-3).
    // Asserted: every estimate within 10 % of 2/R, and the given-kappa
    // tolerances.
    const auto ball_mesh = diffusion_3d(true, 1.5, 3, 0.5, 1e-3, 0.45, "least squares", "half derivative",
                                        [](Abc::EbfParameters &ap) { ap.curvature_from_mesh = true; });
    check(std::abs(ball_mesh[9] - 2. / 1.5) <= 0.1 * 2. / 1.5 && std::abs(ball_mesh[10] - 2. / 1.5) <= 0.1 * 2. / 1.5,
          "ball, curvature from the mesh within 10 % of 2/R: " + std::to_string(ball_mesh[9]) + " .. " +
            std::to_string(ball_mesh[10]));
    check(ball_mesh[2] >= 10. * ball_mesh[1] && ball_mesh[1] < 5.3e-4 && ball_mesh[0] < 4e-3 && ball_mesh[6] <= 0.,
          "ball, half derivative with the mesh's curvature: end " + sci(ball_mesh[1]) +
            " < 5.3e-4, at least 10x closer than Neumann (" + std::to_string(ball_mesh[2] / ball_mesh[1]) +
            "x), max " + sci(ball_mesh[0]) + " < 4e-3, Pi non-increasing");
    const auto cube_half =
      diffusion_3d(false, 1.5, 4, 0.5, 1e-3, 0.45, "least squares", "half derivative", half_derivative(0.));
    check(cube_half[2] >= 10. * cube_half[1] && cube_half[0] < 8e-3 && cube_half[6] <= 0.,
          "cube, half derivative: at least 10x closer than Neumann at t_end (" +
            std::to_string(cube_half[2] / cube_half[1]) + "x), max " + sci(cube_half[0]) +
            " < 8e-3, Pi non-increasing every step");
  }

  /**
   * Exploratory scan (not a ctest case): FEMBALL_SCAN="key=value;..." with
   * shape (ball|cube|disk), fit, form, rcond, dinf, dk, nk, nphi, dt,
   * imposed, ref, t, checksteps, kappa, distributed, rho, history (of the
   * half derivative: exact or sum of exponentials), R (disk radius, 3);
   * dk = 0 is the library's default Delta k; prints the energy
   * errors and the one-step spectral radius.
   */
  void
  femball_scan()
  {
    const char *env = std::getenv("FEMBALL_SCAN");
    std::map<std::string, std::string> kv{{"shape", "ball"}, {"fit", "least squares"}, {"form", "value"},
                                          {"rcond", "0"}, {"dinf", "0.45"}, {"dk", "0"}, {"nk", "20"},
                                          {"nphi", "5"}, {"dt", "1e-3"}, {"imposed", "value"}, {"ref", "3"},
                                          {"t", "0.5"}, {"checksteps", "200"}, {"kappa", "0"}, {"distributed", "0"},
                                          {"rho", "0"}, {"history", "sum of exponentials"}, {"R", "3"}};
    std::string spec = env ? env : "";
    for (std::size_t pos = 0; pos < spec.size();)
      {
        const std::size_t end = std::min(spec.find(';', pos), spec.size());
        const std::string item = spec.substr(pos, end - pos);
        const std::size_t eq   = item.find('=');
        if (eq != std::string::npos)
          kv[item.substr(0, eq)] = item.substr(eq + 1);
        pos = end + 1;
      }
    const auto tweak = [&](Abc::EbfParameters &ap) {
      ap.fit_form                 = kv["form"];
      ap.pseudo_inverse_tolerance = std::stod(kv["rcond"]);
      ap.wave_number_range        = std::stod(kv["dk"]);
      ap.n_wave_numbers           = std::stoi(kv["nk"]);
      ap.n_directions             = std::stoi(kv["nphi"]);
      ap.stability_check_steps    = std::stoi(kv["checksteps"]);
      ap.boundary_curvature       = kv["kappa"] == "mesh" ? 0. : std::stod(kv["kappa"]);
      ap.curvature_radius         = std::stod(kv["rho"]);
      ap.curvature_from_mesh      = kv["kappa"] == "mesh";
      ap.half_derivative_history  = kv["history"];
      if (kv["fit"] != "monotone")
        ap.max_update_norm = 1e10;
    };
    if (root())
      std::cout << "  scan: " << spec << std::endl;
    try
      {
        if (kv["shape"] == "disk")
          {
            const double                R = std::stod(kv["R"]), t_end = std::stod(kv["t"]);
            Fem::FemDiffusionParameters fp;
            fp.time_step = std::stod(kv["dt"]);
            Abc::EbfParameters ap;
            ap.cloud_radius = std::stod(kv["dinf"]);
            ap.fit          = kv["fit"];
            ap.imposed      = kv["imposed"];
            tweak(ap);
            HeatKernel       c0;
            Triangulation<2> tria;
            disk(R, std::stoi(kv["ref"]))(tria);
            Fem::FemDiffusion<2> ebf(tria, fp), neumann(tria, fp);
            ebf.setup(Abc::TruncationBoundary::absorbing, ap, c0);
            neumann.setup(Abc::TruncationBoundary::neumann, ap, c0);
            const BoundingBox<2> all(std::make_pair(Point<2>(-R, -R), Point<2>(R, R)));
            const double         s_end = 1. + 16. * t_end;
            const double         ee    = M_PI / (8. * s_end) * (1. - std::exp(-8. * R * R / s_end));
            const double         e0    = M_PI / 8. * (1. - std::exp(-8. * R * R));
            const unsigned int   n     = static_cast<unsigned int>(std::round(t_end / fp.time_step));
            double               max_e = 0.;
            for (unsigned int k = 1; k <= n; ++k)
              {
                ebf.advance();
                neumann.advance();
                if (k % 100 == 0)
                  {
                    const double s = 1. + 16. * ebf.time();
                    max_e = std::max(max_e, std::abs(ebf.energy(all) - M_PI / (8. * s) * (1. - std::exp(-8. * R * R / s))) / e0);
                  }
              }
            const double end_e = std::abs(ebf.energy(all) - ee) / e0, end_n = std::abs(neumann.energy(all) - ee) / e0;
            const double arnoldi = kv["imposed"] == "half derivative" ? 0. : ebf.arnoldi_spectral_radius(50, 60);
            if (root())
              std::cout << "  disk: EBF end " << sci(end_e) << " max " << sci(max_e) << ", Neumann end " << sci(end_n)
                        << " (ratio " << end_n / end_e << "), Arnoldi " << arnoldi << ", max|V| "
                        << sci(ebf.absorbing_boundary().statistics().max_update_norm) << ", Delta k "
                        << ebf.absorbing_boundary().statistics().wave_number_range << std::endl;
          }
        else
          {
            const bool ball = kv["shape"] == "ball";
            const auto r = diffusion_3d(ball, 1.5, std::stoi(kv["ref"]), std::stod(kv["t"]), std::stod(kv["dt"]),
                                        std::stod(kv["dinf"]), kv["fit"], kv["imposed"], tweak,
                                        kv["distributed"] == "1");
            if (root())
              std::cout << "  RESULT ratio " << r[2] / r[1] << " end " << std::setprecision(13) << r[1] << " max "
                        << r[0] << std::setprecision(6) << std::endl;
          }
      }
    catch (const ParameterError &e)
      {
        if (root())
          std::cout << "  ParameterError: " << e.what() << std::endl;
      }
  }
} // namespace

int
main(int argc, char **argv)
{
  return run(argc, argv,
             {{"rank_invariance_diffusion", rank_invariance_diffusion},
              {"disk_diffusion", disk_diffusion},
              {"half_derivative_history", half_derivative_history},
              {"disk_wave", disk_wave}, {"diffusion_3d_cube_ball", diffusion_3d_cube_ball}, {"rank_invariance_wave", rank_invariance_wave},
              {"disk_wave_scan", disk_wave_scan}, {"disk_wave_compact", disk_wave_compact}, {"disk_wave_cloud_size", disk_wave_cloud_size},
              {"femball_scan", femball_scan}});
}
