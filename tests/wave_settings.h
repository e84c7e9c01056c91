#ifndef perideal_tests_wave_settings_h
#define perideal_tests_wave_settings_h

// Exploratory scans of the EBF wave ABC set-up: "key=value ..." text
// applied on top of a test's Abc::WaveAbcParameters.

#include <perideal/abc/ebf_wave_abc.h>
#include <perideal/abc/wave_abc_layers.h>

#include <map>
#include <sstream>
#include <string>

namespace PeriDEALTests
{
  /** Key/value pairs of "key=value key=value ...". */
  inline std::map<std::string, std::string>
  key_values(const std::string &text)
  {
    std::map<std::string, std::string> kv;
    std::istringstream                 in(text);
    std::string                        item;
    while (in >> item)
      {
        const auto eq = item.find('=');
        kv[item.substr(0, eq)] = eq == std::string::npos ? "1" : item.substr(eq + 1);
      }
    return kv;
  }

  /** @p p with the EBF keys of @p kv applied (form, nphi, dphi, dk, nk, cone, cloud, tol, reg, levels, disp, maxv, thin, curv, wcurv, wk, points, layer, wp, share). */
  inline PeriDEAL::Abc::WaveAbcParameters
  with_wave_settings(PeriDEAL::Abc::WaveAbcParameters p, const std::map<std::string, std::string> &kv)
  {
    const auto num = [&](const std::string &k, const double def) {
      return kv.count(k) ? std::stod(kv.at(k)) : def;
    };
    const auto str = [&](const std::string &k, const std::string &def) { return kv.count(k) ? kv.at(k) : def; };
    p.fit_form                 = str("form", p.fit_form);
    p.n_directions             = static_cast<unsigned int>(num("nphi", p.n_directions));
    p.direction_range          = num("dphi", p.direction_range);
    p.wave_number_range        = num("dk", p.wave_number_range);
    p.n_wave_numbers           = static_cast<unsigned int>(num("nk", p.n_wave_numbers));
    p.cone_angle               = num("cone", p.cone_angle);
    p.cloud_radius             = num("cloud", p.cloud_radius);
    p.pseudo_inverse_tolerance = num("tol", p.pseudo_inverse_tolerance);
    p.pseudo_inverse_regularization = str("reg", p.pseudo_inverse_regularization);
    p.n_time_levels            = static_cast<unsigned int>(num("levels", p.n_time_levels));
    p.dispersion               = str("disp", p.dispersion);
    p.max_update_norm          = num("maxv", p.max_update_norm);
    p.thinning                 = str("thin", p.thinning);
    p.curvature_radius         = num("curv", p.curvature_radius);
    p.wake_curvature_radius    = num("wcurv", p.wake_curvature_radius);
    p.wake_wave_number         = num("wk", p.wake_wave_number);
    p.cloud_points             = str("points", p.cloud_points);
    p.layer_thickness          = num("layer", p.layer_thickness);
    p.wake_angle_exponent      = num("wp", p.wake_angle_exponent);
    p.share_updating_vectors   = num("share", p.share_updating_vectors ? 1. : 0.) != 0.;
    return p;
  }

  // Named E14 layers (2D PD waves, m = 6, dx = 0.25): the library's
  // Abc::WaveAbcLayers (include/perideal/abc/wave_abc_layers.h, where the
  // scans behind them are summarized) at the E14 grid spacing.

  /** Abc::WaveAbcLayers::curved_stable (session 13): 2 dx clouds, rcond 1e-4. */
  inline PeriDEAL::Abc::WaveAbcParameters
  e14_stable_parameters(const double disc_radius)
  {
    return PeriDEAL::Abc::WaveAbcLayers::curved_stable(0.25, disc_radius);
  }

  /** Abc::WaveAbcLayers::curved_tikhonov (session 14): 3 dx clouds, Tikhonov 2e-4. */
  inline PeriDEAL::Abc::WaveAbcParameters
  e14_tikhonov_parameters(const double disc_radius)
  {
    return PeriDEAL::Abc::WaveAbcLayers::curved_tikhonov(0.25, disc_radius);
  }

  /** Abc::WaveAbcLayers::curved_monotone (session 15): 4 dx clouds, cone 0.4, Tikhonov 4e-4. */
  inline PeriDEAL::Abc::WaveAbcParameters
  e14_monotone_parameters(const double disc_radius)
  {
    return PeriDEAL::Abc::WaveAbcLayers::curved_monotone(0.25, disc_radius);
  }

  /**
   * E15 (2D PD waves, m = 3, doc/design.md, session 18) with the source's
   * direction set: n_phi = 10 directions in [-pi/4, pi/4] about the normal
   * (the defaults), made stable by session 14-15's regularization: the
   * increment form, Tikhonov lambda = 1.5e-3 sigma_max, clouds of the points
   * within 3.5 dx (0.875, the largest the ghost layer admits at m = 3) in
   * the wide cone Delta phi = 0.4 (14-15 points), and two changes of the
   * mode set: curved about x_i - R n (R: the disc radius) and wave numbers
   * in [-2, 2] (Delta k = 2, n_k = 10). With Delta k = 1 (the source's) no
   * lambda in 3e-5 .. 1e-2 is stable on the R = 2.5 disc; with plane modes
   * the probe error is no better than the normal-only e15_parameters().
   */
  inline PeriDEAL::Abc::WaveAbcParameters
  e15_source_modes_parameters(const double disc_radius)
  {
    PeriDEAL::Abc::WaveAbcParameters prm;
    prm.dispersion                    = "discrete";
    prm.curvature_radius              = disc_radius;
    prm.wave_number_range             = 2.;
    prm.cloud_radius                  = 0.875;
    prm.cone_angle                    = 0.4;
    prm.pseudo_inverse_tolerance      = 1.5e-3;
    prm.pseudo_inverse_regularization = "tikhonov";
    prm.fit_form                      = "increment";
    return prm;
  }
} // namespace PeriDEALTests

#endif
