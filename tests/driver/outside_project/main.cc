#include <perideal/base/kernel.h>

#include <cmath>
#include <iostream>

int
main()
{
  PeriDEAL::ScalarKernel k;
  k.dim      = 2;
  k.exponent = 2;
  k.delta    = 0.5;
  const double kappa = k.micro_constant_for(1.);
  std::cout << "kappa = " << kappa << std::endl;
  return std::abs(kappa - 4. / (M_PI * 0.25)) < 1e-10 ? 0 : 1;
}
