#include "hof/procedures/needle_model.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hof::procedures {

std::string_view phase_name(NeedlePhase phase) {
  switch (phase) {
    case NeedlePhase::kFree:
      return "free";
    case NeedlePhase::kTouching:
      return "touching";
    case NeedlePhase::kPrePuncture:
      return "pre-puncture";
    case NeedlePhase::kPunctured:
      return "punctured";
    case NeedlePhase::kRelaxation:
      return "relaxation";
    case NeedlePhase::kExtraction:
      return "extraction";
    case NeedlePhase::kOut:
      return "out";
  }
  return "unknown";
}

std::string_view form_name(FungForm form) { return form == FungForm::kIntegrated ? "integrated" : "printed"; }

std::string_view model_name(NeedleForceModel model) {
  return model == NeedleForceModel::kFung ? "fung" : "simone-okamura";
}

namespace {
// A value that overflowed stays finite (the safety filter clamps it; a NaN would only be zeroed).
double finite_or_max(double v) {
  if (std::isnan(v)) return 0.0;
  return std::clamp(v, -std::numeric_limits<double>::max(), std::numeric_limits<double>::max());
}
}  // namespace

double fung_force(const FungParameters& t, double d, FungForm form) {
  // Fung's law (Maurin et al. 2004), integrated: f(d0) = F0; or as the thesis prints it.
  const double exponential = (t.f0_n + t.b_n) * std::exp(t.a_per_m * (d - t.d0_m));
  return finite_or_max(form == FungForm::kIntegrated ? exponential - t.b_n : exponential + t.b_n);
}

double stiffness_force(const StiffnessPolynomial& p, double d) {
  // Simone & Okamura 2002: a0 + a1 d + a2 d².
  return finite_or_max(p.a0_n + p.a1_n_per_m * d + p.a2_n_per_m2 * d * d);
}

double karnopp_force(const KarnoppFriction& k, double inserted_m, double v, double held_n) {
  // Karnopp (1985) as in Okamura, Simone & O'Leary 2004, per unit inserted length (Maurin).
  const double length = std::max(0.0, inserted_m);
  const double half_band = 0.5 * k.velocity_band_m_per_s;
  if (v >= half_band) return finite_or_max(length * (k.static_positive_n_per_m + k.damping_positive_n_s_per_m2 * v));
  if (v <= -half_band)
    return finite_or_max(length * (k.static_negative_n_per_m + k.damping_negative_n_s_per_m2 * std::abs(v)));
  const double low = std::min(length * k.static_negative_n_per_m, length * k.static_positive_n_per_m);
  const double high = std::max(length * k.static_negative_n_per_m, length * k.static_positive_n_per_m);
  return std::clamp(std::isfinite(held_n) ? held_n : 0.0, low, high);
}

double pre_puncture_force(const TissueNeedleParameters& p, double d) {
  // An intact capsule pushes back or not at all: Fung's fit extrapolated above the surface
  // side of d0 (the printed form near d = 0) would draw the needle in.
  return p.model == NeedleForceModel::kFung ? std::max(0.0, fung_force(p.fung_pre, d, p.fung_form))
                                            : stiffness_force(p.stiffness, d);
}

double post_puncture_force(const TissueNeedleParameters& p, double d, double v, double held_n) {
  if (p.model == NeedleForceModel::kFung) return fung_force(p.fung_post, d, p.fung_form);
  return finite_or_max(karnopp_force(p.friction, d, v, held_n) + p.cutting_force_n);
}

double reinsertion_force(const TissueNeedleParameters& p, double d, double v, double held_n) {
  return karnopp_force(p.friction, d, v, held_n);
}

double extraction_force(const TissueNeedleParameters& p, double d, double v, double held_n) {
  return karnopp_force(p.friction, d, v, held_n);
}

double relaxation_force(const TissueNeedleParameters& p, double f0_n, double elapsed_s) {
  // A first-order decay (Maurin 2004 describe a slow decrease while the needle is still; the
  // time constant is a parameter, not a measured value).
  if (!(p.relaxation_time_s > 0.0)) return 0.0;
  return f0_n * std::exp(-std::max(0.0, elapsed_s) / p.relaxation_time_s);
}

Expected<void> validate(const TissueNeedleParameters& p, std::string_view what) {
  const auto bad = [&](std::string_view attribute, std::string_view rule, double value) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: {} must be {}, got {}", what, attribute, rule, value));
  };
  const auto finite = [](double v) { return std::isfinite(v); };
  for (const auto& [name, theta] : {std::pair{"fungPre", p.fung_pre}, std::pair{"fungPost", p.fung_post}}) {
    for (double v : {theta.a_per_m, theta.b_n, theta.d0_m, theta.f0_n}) {
      if (!finite(v)) return bad(name, "four finite numbers (a 1/m, b N, d0 m, F0 N)", v);
    }
  }
  for (double v : {p.stiffness.a0_n, p.stiffness.a1_n_per_m, p.stiffness.a2_n_per_m2}) {
    if (!finite(v)) return bad("stiffness", "three finite numbers (a0 N, a1 N/m, a2 N/m2)", v);
  }
  for (double v : {p.friction.static_positive_n_per_m, p.friction.damping_positive_n_s_per_m2}) {
    // Friction resists the motion: a wrong sign would push the hand along (energy in).
    if (!(finite(v) && v >= 0.0))
      return bad("friction", "Cp, bp >= 0 and Cn, bn <= 0 (N/m, N s/m2; Maurin: 0.121 -0.117 3200 -1600)", v);
  }
  for (double v : {p.friction.static_negative_n_per_m, p.friction.damping_negative_n_s_per_m2}) {
    if (!(finite(v) && v <= 0.0))
      return bad("friction", "Cp, bp >= 0 and Cn, bn <= 0 (N/m, N s/m2; Maurin: 0.121 -0.117 3200 -1600)", v);
  }
  if (!(p.friction.velocity_band_m_per_s >= 0.0 && finite(p.friction.velocity_band_m_per_s))) {
    return bad("frictionVelocityBand", ">= 0 m/s", p.friction.velocity_band_m_per_s);
  }
  if (!finite(p.cutting_force_n)) return bad("cuttingForce", "finite (N)", p.cutting_force_n);
  if (!(p.capsule_m > 0.0 && finite(p.capsule_m))) return bad("capsule", "> 0 m", p.capsule_m);
  if (!(p.puncture_force_n > 0.0 && finite(p.puncture_force_n)))
    return bad("punctureForce", "> 0 N (a large value: by depth only)", p.puncture_force_n);
  if (!(p.relaxation_time_s > 0.0 && finite(p.relaxation_time_s)))
    return bad("relaxationTime", "> 0 s", p.relaxation_time_s);
  if (!(p.lateral_stiffness_n_per_m >= 0.0 && finite(p.lateral_stiffness_n_per_m))) {
    return bad("lateralStiffness", ">= 0 N/m", p.lateral_stiffness_n_per_m);
  }
  if (!(p.lateral_damping_n_s_per_m >= 0.0 && finite(p.lateral_damping_n_s_per_m))) {
    return bad("lateralDamping", ">= 0 N s/m", p.lateral_damping_n_s_per_m);
  }
  if (!(p.spread_radius_m > 0.0 && finite(p.spread_radius_m))) return bad("spreadRadius", "> 0 m", p.spread_radius_m);
  if (!(p.path_tolerance_m > 0.0 && finite(p.path_tolerance_m)))
    return bad("pathTolerance", "> 0 m", p.path_tolerance_m);
  return {};
}

}  // namespace hof::procedures
