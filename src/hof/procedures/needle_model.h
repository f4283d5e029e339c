#pragma once
/// @file
/// Needle insertion force models (pure functions, SI units) and their parameters.
///
/// Sign convention: a force f along the needle is the tissue's force on the needle along the
/// insertion axis, f > 0 resisting insertion (it pushes the needle back out: the hand feels
/// −f·axis), f < 0 drawing the needle in (or holding it back while it is withdrawn).
///
///  - Fung's law per phase (Maurin et al., "In vivo study of forces during needle insertions",
///    MRNV 2004): dT/dλ = a (T + b) integrated gives f(d) = (F0 + b)·e^{a(d − d0)} − b, so that
///    f(d0) = F0. The thesis (and the MATLAB comment it came from) prints "+ b", which gives
///    f(d0) = F0 + 2b. HoF's default is the printed form: with Maurin's θ it starts each phase
///    from ≈0 and its post-puncture force resists insertion, rising toward b = 1.7 N — the
///    shape Maurin et al. measured (resisting forces that drop at each puncture and rise again).
///    The integrated form with the same θ draws the needle in after the puncture (−3.39 N, eight
///    times the puncture force, what the hand would feel), so it stays an option (FungForm) for
///    a θ fitted to it. Before the puncture the force is never below zero (an intact capsule
///    pushes back or not at all; the fit's extrapolation below d0 would pull). Defaults θ = [a, b, d0, F0]:
///    pre-puncture [0.121 /mm, −0.098 N, 11.45 mm, 0.2 N] (0.12 N at the surface, 0.39 N at
///    20 mm), post-puncture [−0.031 /mm, 1.7 N, 19.61 mm, −3.39 N]: taken literally, the
///    post-puncture force is negative (−3.39 N at 19.61 mm, tending to −1.7 N deeper): after the
///    capsule gives way the tissue draws the needle in (the "pop-through"). These values are
///    [S] in reference/literature.md §2a (unverified against Maurin's table); a project can
///    set its own.
///  - Simone & Okamura (ICRA 2002; Okamura, Simone & O'Leary, IEEE TBME 51(10) 2004), as
///    adapted by Maurin: stiffness f(d) = a0 + a1·d + a2·d² before puncture (a0 = 0 N,
///    a1 = 0.002 N/mm, a2 = 0.0023 N/mm²); after puncture the stiffness term is gone (the
///    tissue relaxes at the tip) and Karnopp friction along the shaft plus a cutting force act.
///  - Karnopp friction along the shaft, per unit inserted length L (Maurin's values: static
///    0.121 and −0.117 mN/mm, damping 3.2 and −1.6 mN·s/mm²), with v the axial velocity
///    (> 0 inserting) and Δv the stick band:
///        f = L·(Cp + bp·v)        v ≥ Δv/2        (Cp = 0.121 N/m, bp = 3200 N·s/m²)
///        f = L·(Cn + bn·|v|)      v ≤ −Δv/2       (Cn = −0.117 N/m, bn = −1600 N·s/m²)
///        f = clamp(f_held, L·Cn, L·Cp)  otherwise (stuck: the shaft holds what it carried)
///    The negative-side constants are given signed (as Maurin's table does): both make the
///    force negative, growing in magnitude with speed.

#include <cstdint>
#include <string>
#include <string_view>

#include "hof/core/error.h"

namespace hof::procedures {

/// The phases of an insertion (the thesis' H3D field network: touched, broken, depth).
enum class NeedlePhase : std::uint8_t {
  kFree,         ///< not touching any body it can enter
  kTouching,     ///< on the surface (the zero-force surface lets the tip pass)
  kPrePuncture,  ///< in, the capsule intact: the pre-puncture model
  kPunctured,    ///< the capsule broken, inserting: the post-puncture model
  kRelaxation,   ///< still after insertion: the force decays with time
  kExtraction,   ///< withdrawing: friction along the shaft
  kOut,          ///< withdrawn after a puncture (until the next contact)
};
inline constexpr int kNeedlePhaseCount = 7;
/// "free", "touching", "pre-puncture", "punctured", "relaxation", "extraction", "out".
[[nodiscard]] std::string_view phase_name(NeedlePhase phase);

enum class NeedleForceModel : std::uint8_t {
  kFung,           ///< Maurin et al. 2004: Fung's law per phase
  kSimoneOkamura,  ///< stiffness polynomial, then Karnopp friction + cutting
};
[[nodiscard]] std::string_view model_name(NeedleForceModel model);  ///< "fung", "simone-okamura"

/// Which form of Fung's law θ is read in.
enum class FungForm : std::uint8_t {
  kIntegrated,  ///< f(d) = (F0 + b)·e^{a(d − d0)} − b: Fung's law integrated, f(d0) = F0
  /// f(d) = (F0 + b)·e^{a(d − d0)} + b, as the thesis (and the MATLAB comment it came from)
  /// prints it. With Maurin's θ, F0 + 2b ≈ 0 in both phases (0.004 N and 0.01 N): each phase
  /// starts from about zero at its d0 and rises, the post-puncture force is positive.
  kPrinted,
};
[[nodiscard]] std::string_view form_name(FungForm form);  ///< "integrated", "printed"

/// θ = [a, b, d0, F0] of f(d) = (F0 + b)·e^{a(d − d0)} ∓ b (FungForm).
struct FungParameters {
  double a_per_m{121.0};
  double b_n{-0.098};
  double d0_m{0.01145};
  double f0_n{0.2};
  bool operator==(const FungParameters&) const = default;
};
[[nodiscard]] double fung_force(const FungParameters& theta, double depth_m, FungForm form = FungForm::kIntegrated);

/// f(d) = a0 + a1·d + a2·d².
struct StiffnessPolynomial {
  double a0_n{0.0};
  double a1_n_per_m{2.0};      ///< 0.002 N/mm
  double a2_n_per_m2{2300.0};  ///< 0.0023 N/mm²
  bool operator==(const StiffnessPolynomial&) const = default;
};
[[nodiscard]] double stiffness_force(const StiffnessPolynomial& p, double depth_m);

/// Karnopp friction per unit inserted length (see the file comment).
struct KarnoppFriction {
  double static_positive_n_per_m{0.121};        ///< Cp = Dp (0.121 mN/mm)
  double static_negative_n_per_m{-0.117};       ///< Cn = Dn (−0.117 mN/mm)
  double damping_positive_n_s_per_m2{3200.0};   ///< bp (3.2 mN·s/mm²)
  double damping_negative_n_s_per_m2{-1600.0};  ///< bn (−1.6 mN·s/mm²)
  double velocity_band_m_per_s{0.002};          ///< Δv: |v| < Δv/2 sticks (and counts as still)
  bool operator==(const KarnoppFriction&) const = default;
};
/// Friction on a shaft of inserted length `inserted_m` moving at axial velocity `v`; `held_n`
/// is what the shaft carried when it stuck.
[[nodiscard]] double karnopp_force(const KarnoppFriction& k, double inserted_m, double v, double held_n);

/// How a body responds to the needle: one set per body (a later tissue region, a tumour, gets
/// its own). Defaults: the literature's (see the file comment), the thesis' capsule distance
/// (LiverFungForceEffect capsule = 0.02 m) and iMSTK's puncture threshold (3 N).
struct TissueNeedleParameters {
  bool pierceable{true};
  NeedleForceModel model{NeedleForceModel::kFung};
  FungForm fung_form{FungForm::kPrinted};  ///< see the file comment: the form that resists insertion
  FungParameters fung_pre{};
  FungParameters fung_post{-31.0, 1.7, 0.01961, -3.39};
  StiffnessPolynomial stiffness{};
  double cutting_force_n{0.0};  ///< Simone–Okamura after puncture, at the tip
  KarnoppFriction friction{};
  double capsule_m{0.02};                   ///< depth at which the capsule breaks
  double puncture_force_n{3.0};             ///< or the force at which it breaks (first reached)
  double relaxation_time_s{2.0};            ///< time constant of the decay while still
  double lateral_stiffness_n_per_m{500.0};  ///< the tissue holding the shaft on its path (≤ the device's)
  double lateral_damping_n_s_per_m{1.0};
  double spread_radius_m{0.01};  ///< the reaction's reach around the path in the tissue
  /// How far the tip may leave its path sideways before the needle tears out of it (the
  /// needle is then withdrawn: a rigid needle cannot move across the tissue).
  double path_tolerance_m{0.02};
  bool operator==(const TissueNeedleParameters&) const = default;
};
/// Checks that every value is finite and in range; errors name `what` and the attribute.
[[nodiscard]] Expected<void> validate(const TissueNeedleParameters& p, std::string_view what);

/// The model's axial force before puncture at depth d (> 0).
[[nodiscard]] double pre_puncture_force(const TissueNeedleParameters& p, double depth_m);
/// After puncture while inserting new tissue (Fung: the post-puncture law; Simone–Okamura:
/// friction on the inserted length plus cutting). Through a path already cut (pushed back in
/// after a withdrawal) only friction acts: reinsertion_force().
[[nodiscard]] double post_puncture_force(const TissueNeedleParameters& p, double depth_m, double v, double held_n);
/// Pushed back in along a path already cut: Karnopp friction on the inserted length.
[[nodiscard]] double reinsertion_force(const TissueNeedleParameters& p, double depth_m, double v, double held_n);
/// While withdrawing: Karnopp friction on the inserted length (both models).
[[nodiscard]] double extraction_force(const TissueNeedleParameters& p, double depth_m, double v, double held_n);
/// While still after insertion: the force f0 it had when it stopped, decaying.
[[nodiscard]] double relaxation_force(const TissueNeedleParameters& p, double f0_n, double elapsed_s);

}  // namespace hof::procedures
