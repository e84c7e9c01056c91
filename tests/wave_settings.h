#ifndef perideal_tests_wave_settings_h
#define perideal_tests_wave_settings_h

// Exploratory scans of the EBF wave ABC set-up: "key=value ..." text
// applied on top of a test's Abc::WaveAbcParameters.

#include <perideal/abc/ebf_wave_abc.h>

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

  /** @p p with the EBF keys of @p kv applied (form, nphi, dphi, dk, nk, cone, cloud, tol, reg, levels, disp, maxv, thin, curv, wake, wakew, wcurv, wk). */
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
    p.wake_modes               = str("wake", p.wake_modes);
    p.wake_mode_weight         = num("wakew", p.wake_mode_weight);
    p.wake_curvature_radius    = num("wcurv", p.wake_curvature_radius);
    p.wake_wave_number         = num("wk", p.wake_wave_number);
    return p;
  }
} // namespace PeriDEALTests

#endif
