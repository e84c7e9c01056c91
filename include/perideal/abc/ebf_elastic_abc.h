#ifndef perideal_abc_ebf_elastic_abc_h
#define perideal_abc_ebf_elastic_abc_h

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>
#include <deal.II/base/types.h>

#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/discretization/discretization.h>
#include <perideal/discretization/domain.h>
#include <perideal/models/bond_based.h>

#include <array>
#include <complex>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace PeriDEAL
{
  namespace Abc
  {
    /**
     * Dispersion of the vector far-field modes of 2D bond-based PD
     * elasticity (dissertation Sect. 4.3.2-4.3.3): for the wave vector
     * k n the symmetric "generalized mass" (acoustic) matrix
     * M(k n) / rho with rho omega^2 gamma = M gamma, whose two eigenpairs
     * are the P mode (polarization nearest to n) and the S mode (4.150)-(4.151).
     * With a damping d (rho u'' = F - 2 rho d u') the modes decay as exp(-d t)
     * and omega~ = sign(k) sqrt(lambda - d^2), as for the scalar waves (4.57).
     */
    class ElasticDispersion
    {
    public:
      /** One outgoing mode: frequency omega~ and unit real polarization gamma. */
      struct Mode
      {
        std::complex<double> frequency;
        Tensor<1, 2>         polarization;
      };

      /**
       * Classical plane stress (nu = 1/3) or plane strain (nu = 1/4)
       * elasticity (4.105)-(4.110): c_P^2 = E/(rho (1 - nu^2)) resp.
       * E (1 - nu)/(rho (1 + nu)(1 - 2 nu)), c_S^2 = E/(2 rho (1 + nu)).
       */
      static ElasticDispersion
      local(const double youngs_modulus, const bool plane_stress, const double density,
            const double damping);
      /**
       * The discrete matrix (4.144)-(4.147) of the linearized bond-based
       * near field: M(k) = sum_j c omega(min(|xi_j|, delta)) beta_j dx^2
       * xi_j xi_j^T / |xi_j|^3 (1 - cos(k . xi_j)) over the lattice family
       * of the origin, with the micromodulus and volume factors exactly as
       * BondBasedOperator / Discretization compute them.
       */
      static ElasticDispersion
      discrete(const BondBasedModelParameters &model, const LatticeParameters &lattice,
               const double density, const double damping);
      /** M(k) = sum_j w_j xi_j xi_j^T (1 - cos(k . xi_j)) for an explicit stencil. */
      static ElasticDispersion
      stencil(const std::vector<Tensor<1, 2>> &offsets, const std::vector<double> &weights,
              const double density, const double damping, const std::string &name);

      /** M(k) / rho for the wave vector @p k. */
      Tensor<2, 2>
      acoustic_matrix(const Tensor<1, 2> &k) const
      {
        return acoustic(k);
      }
      /**
       * The P (first) and S (second) modes of signed wave number @p k along
       * the unit direction @p n: eigenpairs of M(|k| n)/rho, P the one whose
       * polarization is nearer to n; signs with gamma_P . n > 0 and
       * gamma_S . n_perp > 0 (n_perp = (-n_2, n_1)). k = 0: gamma_P = n,
       * gamma_S = n_perp. omega~ carries the sign of k, so that the mode set
       * over [-Delta k, Delta k] is closed under complex conjugation.
       */
      std::array<Mode, 2>
      modes(const double k, const Tensor<1, 2> &n) const;

      double      damping = 0.;
      std::string name;

    private:
      std::function<Tensor<2, 2>(const Tensor<1, 2> &)> acoustic;
    };

    /**
     * EBF absorbing boundary for 2D elastic waves (Sect. 4.3.4): per owned
     * absorbing node the cloud of the conic region behind it (as in
     * EbfWaveAbc), the outgoing P and S modes gamma exp(i k n.x - i omega~ t)
     * for k in [-Delta k, Delta k] and directions within Delta phi of the
     * outward normal (4.153)-(4.158), the moment matrices M_G, M_H of both
     * displacement (velocity) components and two time levels, and the 2 x 4
     * updating blocks per cloud point: u_i^{n+1} = sum_j V_G,j (u_j^n, u_j^{n-1})
     * (4.166). The guards (condition number, max |V|) are enforced by
     * thinning the cloud (Fig. 4.23), else ParameterError. As for the
     * scalar EbfWaveAbc: "Curvature radius" rho > 0 evaluates every mode
     * about x_i - rho n in polar coordinates with the cylindrical amplitude
     * sqrt(rho / r) and the polarization turned with the radial direction,
     * "Fit form" = increment fits the change over one step, and
     * "Pseudo-inverse regularization" = tikhonov weights the singular
     * values as sigma/(sigma^2 + lambda^2) (ElasticAbcLayers).
     *
     * With "Method" = "first order" the same update form holds the
     * conventional baseline instead: the Lysmer-type one-way condition
     * u^{n+1} = u^n - dt (C du/dn + d u^n), C = c_P n n^T + c_S (I - n n^T)
     * with the long-wave (k -> 0) P and S speeds of the relation along the
     * normal n, du/dn from a linear least-squares fit over x_i and the cone
     * points within min(d_inf, 2 dx); v alike (doc/design.md, session 18).
     */
    class EbfElasticAbc
    {
    public:
      void
      reinit(const std::vector<Point<2>>                &points,
             const std::vector<types::global_dof_index> &ids,
             const std::vector<unsigned int>            &absorbing,
             const std::vector<Tensor<1, 2>>            &outward_normals,
             const ElasticDispersion                    &dispersion,
             const double                                time_step,
             const double                                dx,
             const WaveAbcParameters                    &parameters,
             const MPI_Comm                              comm);

      /**
       * u_new[2 a + p], v_new[2 a + p]: component p of the extrapolated
       * displacement and velocity of absorbing node a from the components
       * u[q][j], u_old[q][j] (local numbering, ghosts valid).
       */
      void
      compute(const std::array<const double *, 2> &u,
              const std::array<const double *, 2> &u_old,
              const std::array<const double *, 2> &v,
              const std::array<const double *, 2> &v_old,
              std::vector<double>                 &u_new,
              std::vector<double>                 &v_new) const;

      const std::vector<unsigned int> &
      absorbing_points() const
      {
        return absorbing;
      }
      /** Sorted unique local indices of all cloud points. */
      const std::vector<unsigned int> &
      cloud_points() const
      {
        return all_cloud_points;
      }
      /** n_modes counts the P and the S modes. */
      const WaveCloudStatistics &
      statistics() const
      {
        return stats;
      }

    private:
      std::vector<unsigned int> absorbing, cloud_start, cloud_index, all_cloud_points;
      /** Per cloud entry 8 coefficients [p][q][level] of V_G and V_H. */
      std::vector<double> vg, vh;
      WaveCloudStatistics stats;
    };

    /**
     * Long-run stable, accurate EBF layers for 2D bond-based PD elastic
     * waves on a disc near field (E16, dissertation Sect. 4.3.5), the
     * elastic counterpart of WaveAbcLayers for the scalar waves
     * (doc/design.md, session 19).
     */
    namespace ElasticAbcLayers
    {
      /**
       * The E16 mode set (P and S modes in 3 directions within pi/8 of the
       * normal, clouds of radius delta, two time levels, the discrete
       * relation) with five changes that make one setting work for pulses
       * of different widths: wave numbers k dx in {0, +-1/4, ..., +-1}
       * (Delta k = 1/dx, 8 intervals instead of 2), modes curved about
       * x_i - R n (R: @p disc_radius) with cylindrical amplitude and
       * polarization, the increment fit form, the Tikhonov pseudo-inverse
       * sigma/(sigma^2 + lambda^2), lambda = 3e-3 sigma_max (without it
       * more wave numbers grow or break the guard), and the wide
       * extrapolation region Cone angle 0.4 (|y| < cot(0.4) |x| behind
       * x_i, as WaveAbcLayers::curved_monotone) instead of pi/4.
       * max |V| <= 2: in the increment form the level-n coefficient of x_i
       * is 1 plus the fitted increment (measured max |V| 1.12).
       * Measured at delta = 3 dx, dt 0.5, d 0.02 (doc/design.md, session
       * 19): 25-870x closer than the first-order ABC on R = 16 (w 2.5) and
       * R = 32 (w 5), one-step radius 1 - 6.0e-3 on the R = 7 disc (lambda
       * 1.5e-3 .. 6e-3 all below 1), and the R = 32 energy decaying
       * to 1.6e-82 E0 by t = 5000 without a rise between samples 10 steps
       * apart.
       */
      inline WaveAbcParameters
      curved_tikhonov(const double grid_spacing, const double disc_radius)
      {
        WaveAbcParameters prm;
        prm.dispersion                    = "discrete";
        prm.wave_number_range             = 1. / grid_spacing;
        prm.n_wave_numbers                = 8;
        prm.n_directions                  = 2;
        prm.direction_range               = M_PI / 8.;
        prm.cone_angle                    = 0.4;
        prm.cloud_radius                  = 0.;
        prm.n_time_levels                 = 2;
        prm.max_update_norm               = 2.;
        prm.curvature_radius              = disc_radius;
        prm.fit_form                      = "increment";
        prm.pseudo_inverse_regularization = "tikhonov";
        prm.pseudo_inverse_tolerance      = 3e-3;
        return prm;
      }
    } // namespace ElasticAbcLayers

    /** Treatment of the truncation layer of an elastic near field. */
    enum class ElasticTruncation
    {
      /** The EBF absorbing boundary. */
      absorbing,
      /** A free PD surface (traction-free, reflecting). Also the extended reference. */
      free,
      /** The layer nodes held at u = v = 0 (reflecting). */
      fixed,
      /**
       * Only the damping sponge of WaveAbcParameters ("Sponge damping",
       * "Sponge thickness", "Sponge exponent"): nothing overwritten, the
       * damping d + sigma(x) >= 0 per node (energy-stable, doc/design.md
       * session 7). The @p keep filter of setup() exempts nodes as for the layer.
       */
      sponge,
      /**
       * The perfectly matched layer of WaveAbcParameters ("PML damping",
       * "PML thickness", "PML exponent"; doc/design.md, sessions 8-9): the
       * outermost w of the near field, where the normal part of each bond
       * (weight (n . e)^2, e = xi/|xi|) has its elongation e . (u_j - u_i)
       * complex-stretched with one memory per bond and the summed force one
       * memory per node and component (PmlBand). Nothing is overwritten.
       * Not with a @p keep filter (the whole truncation boundary absorbs)
       * and only for the linearized model.
       */
      pml
    };

    /** Density, time step and damping of an elastic wave run. */
    struct ElasticWaveParameters
    {
      double density   = 1.;
      double time_step = 0.;
      /** d of rho u'' = F - 2 rho d u' (>= 0). */
      double damping = 0.;
    };

    /**
     * 2D bond-based PD (linearized, or the PMB with bond breaking) on a
     * truncated domain with velocity Verlet (3.5)-(3.6) and the EBF
     * absorbing boundary on the nodes within delta_L of the truncation
     * boundary (Sect. 4.3.5, 4.3.6), or a damping sponge or a PML
     * (ElasticTruncation; ElasticTruncation::absorbing follows
     * "Absorbing boundary/Method": ebf, first order, sponge or pml); optionally a prescribed-velocity region
     * (impact) and pre-cracks. Any number of ranks.
     */
    class PdUnboundedElastic
    {
    public:
      using VectorField = std::array<Vector, 2>;

      explicit PdUnboundedElastic(const MPI_Comm comm);

      /**
       * @p initial: the initial displacement (2 components). @p keep (optional)
       * selects which nodes of the boundary layer absorb (e.g. not those at a
       * physical free surface): called with the node and its outward normal.
       */
      void
      setup(const Domain<2>                                               &domain,
            const LatticeParameters                                       &lattice,
            const BondBasedModelParameters                                &model,
            const ElasticWaveParameters                                   &wave,
            const ElasticTruncation                                        truncation,
            const WaveAbcParameters                                       &abc,
            const Function<2>                                             &initial,
            const std::function<bool(const Point<2> &, const Tensor<1, 2> &)> &keep = {});

      /** Pre-crack along [a, b] (bonds crossing it break); recomputes the acceleration. */
      void
      add_precrack(const Point<2> &a, const Point<2> &b);
      /** Nodes with @p region(x) move with velocity v(x, t) from now on. */
      void
      set_prescribed_velocity(const std::function<bool(const Point<2> &)>               &region,
                              const std::function<Tensor<1, 2>(const Point<2> &, double)> &v);

      /** One velocity-Verlet step with the absorbing update. */
      void
      advance();

      /**
       * Spectral radius of the linear one-step map of the whole truncated
       * system (linearized model, serial, at most @p max_size state
       * entries, else ParameterError): the state (u, v of all nodes,
       * u^{n-1}, v^{n-1} of the cloud points, the PML memories) is mapped column by column
       * through advance() and the eigenvalues of the dense matrix are
       * computed by LAPACK; the solver state is restored. The number of
       * eigenvalues of modulus > 1 + 1e-8 goes to @p n_unstable if given.
       * A diagnostic of the coupled near-field/ABC recursion, which the
       * per-cloud guards do not control (doc/design.md).
       */
      double
      one_step_spectral_radius(const unsigned int max_size = 4000, unsigned int *n_unstable = nullptr);

      /** Kinetic and strain energy (4.169) of the nodes with inside(x) (all ranks). */
      std::array<double, 2>
      energy(const std::function<bool(const Point<2> &)> &inside) const;
      /**
       * The energy velocity Verlet conserves exactly for the undamped
       * linearized free near field (the modified energy of a linear system),
       * kinetic + strain - dt^2/8 sum_i rho |f_i/rho|^2 V_i over all nodes,
       * f the force of the last step (with the PML correction). The plain
       * kinetic + strain energy at whole steps oscillates by O(dt^2) even
       * then, so monotonicity checks at fine sampling use this one.
       */
      double
      verlet_energy() const;
      /** (x, u, damage) of the nodes with inside(x), gathered on all ranks in id order. */
      struct NodeState
      {
        types::global_dof_index id;
        Point<2>                position;
        Tensor<1, 2>            displacement, velocity;
        double                  damage;
      };
      std::vector<NodeState>
      gather(const std::function<bool(const Point<2> &)> &inside) const;

      double
      time() const
      {
        return t;
      }
      double
      time_step() const
      {
        return dt;
      }
      const Discretization<2> &
      discretization() const
      {
        return disc;
      }
      const EbfElasticAbc &
      absorbing_boundary() const
      {
        return abc;
      }
      const BondBasedOperator<2> &
      model() const
      {
        return *op;
      }
      const ElasticDispersion &
      dispersion() const
      {
        return *relation;
      }
      /** Number of nodes of the truncation layer (absorbing, fixed or PML), all ranks. */
      types::global_dof_index n_layer_nodes = 0;
      /** Wall seconds in the ABC update and in the whole of advance(). */
      double abc_seconds = 0., step_seconds = 0.;

    private:
      Discretization<2>                     disc;
      std::unique_ptr<BondBasedOperator<2>> op;
      std::unique_ptr<ElasticDispersion>    relation;
      EbfElasticAbc                         abc;
      /** The PML band (ElasticTruncation::pml), else empty. */
      PmlBand<2>                            pml_band;
      VectorField                           u, v, a, f;
      std::array<std::vector<double>, 2>    u_old, v_old;
      std::vector<double>                   u_abc, v_abc;
      /** Fixed truncation: the held layer nodes. */
      std::vector<unsigned int> fixed_nodes;
      std::vector<unsigned int> held_nodes;
      std::function<Tensor<1, 2>(const Point<2> &, double)> held_velocity;
      double rho = 1., dt = 0., t = 0., d = 0.;
      /** d + sigma(x_i) per owned node (the sponge; d without one). */
      std::vector<double> damping;
      ElasticTruncation truncation = ElasticTruncation::free;

      void
      compute_acceleration();
    };

    /** Energy history of a run (samples at equal intervals, t = 0 included). */
    struct ElasticRunHistory
    {
      std::vector<double> times;
      /** Kinetic and strain energy (4.169) of the compared region. */
      std::vector<double> kinetic, strain;
      /** Total energy of the whole near field. */
      std::vector<double> total;
      /** PdUnboundedElastic::verlet_energy() of the whole near field. */
      std::vector<double> verlet;
      /** Node states of the compared region at the final time (id order). */
      std::vector<PdUnboundedElastic::NodeState> final_state;
      WaveCloudStatistics                        stats;
      types::global_dof_index                    n_nodes = 0, n_layer_nodes = 0;
      double                                     abc_seconds = 0., step_seconds = 0.;

      /** kinetic + strain of sample @p s. */
      double
      energy(const unsigned int s) const
      {
        return kinetic[s] + strain[s];
      }
    };

    /**
     * Set up @p solver (see PdUnboundedElastic::setup) and run it to
     * @p final_time, sampling the energies @p n_samples + 1 times; @p region
     * is the compared region (e.g. the truncated domain less its layer).
     * With ElasticTruncation::free on a domain large enough that no wave
     * returns to @p region before @p final_time this is the extended-domain
     * reference of Sect. 4.3.5 (reference_radius()).
     */
    ElasticRunHistory
    run_elastic_waves(PdUnboundedElastic                                &solver,
                      const double                                       final_time,
                      const unsigned int                                 n_samples,
                      const std::function<bool(const Point<2> &)>       &region);

    /**
     * Radius of a free reference disc around a source of radius
     * @p source_radius such that a front of speed @p speed leaving the
     * source at t = 0 is not back inside radius @p compared_radius before
     * @p final_time (plus @p margin).
     */
    inline double
    reference_radius(const double speed, const double final_time, const double source_radius,
                     const double compared_radius, const double margin)
    {
      return 0.5 * (speed * final_time + source_radius + compared_radius) + margin;
    }
  } // namespace Abc
} // namespace PeriDEAL

#endif
