#include "hof/coupling/press_recorder.h"

#include <algorithm>
#include <cmath>

#include "hof/coupling/session.h"

namespace hof::coupling {

PressRecorder::PressRecorder(const Session& session, double unit_scale)
    : session_(session), bin_width_(kBinWidthM / unit_scale), fit_from_(kFitFromM / unit_scale) {
  presses_.reserve(16);
}

double PressRecorder::add(const haptics::HapticSample& s) {
  if (!s.valid) return 0.0;
  const bool touching = s.contact && s.triangle >= 0;
  if (!touching) {
    // A press ends once the stylus has been clear for kGapS.
    if (in_press_ && s.time_s - last_contact_s_ > kGapS) in_press_ = false;
    return 0.0;
  }
  // Indentation: how far the surface at the contact has moved inward since the press began
  // (its displacement from rest, less what it had moved before — a body that sagged under
  // gravity before the probe arrived is not indented by the sag).
  const double from_rest =
      (session_.rest_point(s.triangle, s.barycentric, s.layer) - s.contact_point).dot(s.contact_normal);
  if (!in_press_) {
    in_press_ = true;
    Press p;
    p.index = static_cast<std::int32_t>(presses_.size()) + 1;
    p.body = session_.body_of_triangle(s.triangle, s.layer);
    p.start_s = s.time_s;
    p.first_contact = s.contact_point;
    presses_.push_back(p);
    displaced_at_start_ = from_rest;
    last_indentation_ = 0.0;
  }
  last_contact_s_ = s.time_s;
  Press& p = presses_.back();
  const double indentation = from_rest - displaced_at_start_;
  const double force = s.force.norm();
  p.end_s = s.time_s;
  p.max_force_n = std::max(p.max_force_n, force);
  p.max_indentation_m = std::max(p.max_indentation_m, indentation);
  // Loading only (the indentation at its deepest so far): unloading retraces a lower curve
  // (the tissue's damping) and would blur the comparison between presses.
  const bool loading = indentation >= 0.0 && indentation >= last_indentation_;
  if (loading && force >= p.max_loading_force_n) {
    p.max_loading_force_n = force;
    p.indentation_at_max_force = indentation;
  }
  if (loading) {
    const auto bin = static_cast<std::size_t>(indentation / bin_width_);
    if (bin < p.loading_count.size()) {
      p.loading_force_sum[bin] += force;
      ++p.loading_count[bin];
    }
    update_stiffness(p);  // only the loading curve changes it
  }
  last_indentation_ = std::max(last_indentation_, indentation);
  return indentation;
}

void PressRecorder::update_stiffness(Press& p) const {
  // Over the loading curve's bins up to the peak force (past it the tissue gives way or the
  // probe turns back): F ≈ k·d by least squares through the origin, each bin its mean.
  double df = 0.0, dd = 0.0;
  for (std::size_t b = 0; b < p.loading_count.size(); ++b) {
    const double d = (static_cast<double>(b) + 0.5) * bin_width_;
    if (d > p.indentation_at_max_force + bin_width_) break;
    if (d < fit_from_ || p.loading_count[b] == 0) continue;
    df += d * p.loading_force_sum[b] / p.loading_count[b];
    dd += d * d;
  }
  p.stiffness = dd > 0.0 ? df / dd : 0.0;
}

double PressRecorder::force_at(const Press& press, double indentation) const {
  if (!(indentation >= 0.0)) return -1.0;
  const auto bin = static_cast<std::size_t>(indentation / bin_width_);
  if (bin >= press.loading_count.size() || press.loading_count[bin] == 0) return -1.0;
  return press.loading_force_sum[bin] / press.loading_count[bin];
}

}  // namespace hof::coupling
