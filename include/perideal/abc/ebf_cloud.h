#ifndef perideal_abc_ebf_cloud_h
#define perideal_abc_ebf_cloud_h

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>
#include <deal.II/base/types.h>

#include <Eigen/Dense>

#include <array>
#include <map>
#include <utility>
#include <vector>

namespace PeriDEAL
{
  namespace Abc
  {
    using namespace dealii;

    /**
     * Building blocks of the EBF clouds shared by the absorbing boundaries
     * (dissertation Sect. 4.2.3, 4.3.4): the candidates of the conic
     * extrapolation region (4.86) behind an absorbing node in its local
     * frame, their thinning to an auxiliary grid (Fig. 4.23), and the
     * Moore-Penrose fit V = Psi M^+ with its condition number.
     */
    template <int dim>
    class EbfCloudBuilder
    {
    public:
      /** A cloud point: local index and position x bar in the local frame. */
      using Entry = std::pair<unsigned int, Tensor<1, dim>>;

      /**
       * Bin @p points (local numbering, owned and ghost) for searches of
       * radius @p radius; @p ids orders the clouds rank-independently.
       */
      EbfCloudBuilder(const std::vector<Point<dim>>              &points,
                      const std::vector<types::global_dof_index> &ids,
                      const double                                radius,
                      const double                                cone_angle,
                      const double                                dx);

      /**
       * Point @p i first, then the points within the radius in the cone
       * x bar < 0, |y bar| < cot(cone angle) |x bar| of the frame @p R
       * (rows: outward normal, tangent), sorted by global id.
       */
      std::vector<Entry>
      cone(const unsigned int i, const Tensor<2, dim> &R) const;

      /**
       * Stride 1: @p cone itself. Stride s > 1: the first entry and the
       * candidate nearest to each node of the auxiliary grid of spacing
       * s dx in the cone (within s dx / 2), sorted by global id.
       */
      std::vector<Entry>
      thin(const std::vector<Entry> &cone, const unsigned int stride) const;

    private:
      const std::vector<Point<dim>>              &points;
      const std::vector<types::global_dof_index> &ids;
      double                                      radius, cone_slope, dx, bin_width;
      std::map<std::array<long, dim>, std::vector<unsigned int>> bins;

      std::array<long, dim>
      bin_of(const Point<dim> &p) const;
    };

    /**
     * The cloud of a fixed size (session 19, "Cloud size"): @p cone[0]
     * (x_i) and the @p n entries of @p cone nearest to it (distance |x bar|),
     * plus every further entry at the n-th distance up to 1e-9 @p dx (ties
     * kept, so that symmetric clouds stay symmetric), sorted by @p ids of
     * the points. Equivalent to a per-node radius grown until the cloud
     * holds n points. Throws ParameterError naming "Absorbing
     * boundary/Cloud size" if the cone holds fewer than n points.
     */
    template <int dim>
    std::vector<std::pair<unsigned int, Tensor<1, dim>>>
    nearest_cloud_points(const std::vector<std::pair<unsigned int, Tensor<1, dim>>> &cone,
                         const unsigned int                                          n,
                         const std::vector<types::global_dof_index>                 &ids,
                         const double                                                dx,
                         const double                                                search_radius);

    /** Result of one moment-matrix fit. */
    struct PseudoInverseFit
    {
      /** Real part of Psi M^+ (one row per row of Psi). */
      Eigen::MatrixXd V;
      /** Condition number of M over the retained singular values. */
      double condition_number = 0.;
      /** max |(Psi M^+)_ij| (complex modulus). */
      double max_norm = 0.;
    };

    /**
     * V = Psi M^+ by one SVD of the moment matrix @p M; singular values
     * below @p tolerance sigma_max are dropped (0: Eigen's default
     * max(rows, cols) epsilon). With @p tikhonov the weights are
     * sigma/(sigma^2 + lambda^2), lambda = @p tolerance sigma_max, instead
     * (only round-off singular values dropped), and the condition number is
     * sigma_max / max(sigma_min, lambda). For a conjugate-closed mode set and
     * real data V is real up to round-off.
     */
    PseudoInverseFit
    pseudo_inverse_fit(const Eigen::MatrixXcd &M,
                       const Eigen::MatrixXcd &psi,
                       const double            tolerance,
                       const bool              tikhonov = false);
  } // namespace Abc
} // namespace PeriDEAL

#endif
