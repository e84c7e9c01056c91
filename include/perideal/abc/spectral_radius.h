// ---------------------------------------------------------------------
// Spectral radius of a dense one-step map, shared by the PD and FEM wave
// ABC stability diagnostics.
// ---------------------------------------------------------------------
#ifndef perideal_abc_spectral_radius_h
#define perideal_abc_spectral_radius_h

#include <deal.II/lac/lapack_full_matrix.h>

#include <complex>

namespace PeriDEAL
{
  namespace Abc
  {
    /**
     * Largest eigenvalue modulus of @p map (computed in place). Optionally
     * counts the eigenvalues of modulus > 1 + 1e-8 and returns the dominant
     * eigenvalue.
     */
    double
    spectral_radius(dealii::LAPACKFullMatrix<double> &map,
                    unsigned int                     *n_unstable = nullptr,
                    std::complex<double>             *dominant   = nullptr);
  } // namespace Abc
} // namespace PeriDEAL

#endif
