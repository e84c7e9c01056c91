// The stepping of Abc::PdUnboundedWave as it was before session 12 (every
// PD operator row, the old time levels as full-size arrays copied at the
// cloud points, EbfWaveAbc::compute()), for wave_abc.compact_levels. It is
// compiled with the library's optimization flags (tests.cmake), so that
// the compilers contract the same expressions alike and the comparison
// with advance() can be bit for bit.

#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/models/diffusion.h>

#include <vector>

namespace WaveAbcTests
{
  using namespace PeriDEAL;
  using Vector = PeriDEAL::Vector;

  void
  reference_steps(const Discretization<2>     &disc,
                  const Abc::EbfWaveAbc<2>    &abc,
                  const DiffusionOperator<2>  &op,
                  const std::vector<double>   &damping,
                  const double                 dt,
                  const unsigned int           n_steps,
                  Vector                      &u)
  {
    const unsigned int n_owned = disc.n_owned(), n_local = n_owned + disc.n_ghost();
    Vector             v, a, Lu;
    for (Vector *x : {&v, &a, &Lu})
      disc.initialize_vector(*x);
    u.update_ghost_values();
    op.apply(u, Lu);
    for (unsigned int i = 0; i < n_owned; ++i)
      a.local_element(i) = Lu.local_element(i);
    std::vector<double> u_old(u.begin(), u.begin() + n_local), v_old(v.begin(), v.begin() + n_local);
    std::vector<double> u_abc, v_abc;
    const std::vector<unsigned int> &nodes = abc.absorbing_points();
    const double                     half  = 0.5 * dt;
    double *uu = u.begin(), *vv = v.begin(), *aa = a.begin();
    const double *lu = Lu.begin();
    for (unsigned int s = 0; s < n_steps; ++s)
      {
        abc.compute(uu, u_old.data(), vv, v_old.data(), u_abc, v_abc);
        for (const unsigned int j : abc.cloud_points())
          {
            u_old[j] = uu[j];
            v_old[j] = vv[j];
          }
        for (unsigned int i = 0; i < n_owned; ++i)
          {
            uu[i] += dt * (vv[i] + half * aa[i]);
            vv[i] += half * aa[i];
          }
        for (unsigned int c = 0; c < nodes.size(); ++c)
          uu[nodes[c]] = u_abc[c];
        u.update_ghost_values();
        op.apply(u, Lu);
        for (unsigned int i = 0; i < n_owned; ++i)
          {
            const double scale = 1. / (1. + dt * damping[i]);
            vv[i]              = scale * (vv[i] + half * lu[i]);
            aa[i]              = lu[i] - 2. * damping[i] * vv[i];
          }
        for (unsigned int c = 0; c < nodes.size(); ++c)
          vv[nodes[c]] = v_abc[c];
        v.update_ghost_values();
      }
  }
} // namespace WaveAbcTests
