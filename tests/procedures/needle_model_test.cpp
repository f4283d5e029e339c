// The needle force models against their closed forms and the published values.

#include "hof/procedures/needle_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace hof::procedures {
namespace {

TEST(NeedleModel, FungPrePunctureReproducesMaurinsAnchorValues) {
  // reference/literature.md §2a: with the integrated form, f(11.45 mm) = 0.20 N, f(21.45 mm)
  // = 0.44 N, f(31.45 mm) = 1.24 N, f(36.45 mm) ≈ 2.2 N.
  const FungParameters pre;
  EXPECT_NEAR(fung_force(pre, 0.01145), 0.2, 1e-12);
  EXPECT_NEAR(fung_force(pre, 0.02145), 0.44, 0.005);
  EXPECT_NEAR(fung_force(pre, 0.03145), 1.24, 0.01);
  EXPECT_NEAR(fung_force(pre, 0.03645), 2.2, 0.05);
  // Not the printed "+ b" form, which would give F0 + 2b at d0.
  EXPECT_GT(std::abs(fung_force(pre, 0.01145) - (0.2 + 2 * -0.098)), 0.1);
}

TEST(NeedleModel, FungPostPunctureIsTheLiteralFitWithItsSign) {
  // The integrated form (an option): Maurin's θ taken literally draws the needle in.
  TissueNeedleParameters p;
  p.fung_form = FungForm::kIntegrated;
  EXPECT_NEAR(fung_force(p.fung_post, 0.01961), -3.39, 1e-12);
  // Deeper it tends to −b = −1.7 N, from below (a < 0, F0 + b < 0).
  EXPECT_NEAR(fung_force(p.fung_post, 1.0), -1.7, 1e-6);
  EXPECT_LT(fung_force(p.fung_post, 0.03), fung_force(p.fung_post, 0.04));
  // At the thesis' capsule depth the force drops from the pre-puncture rise to the post fit.
  EXPECT_GT(pre_puncture_force(p, 0.02), 0.3);
  EXPECT_LT(post_puncture_force(p, 0.02, 0.01, 0.0), -3.0);
}

TEST(NeedleModel, SimoneOkamuraStiffnessIsThePolynomialInMillimetres) {
  TissueNeedleParameters p;
  p.model = NeedleForceModel::kSimoneOkamura;
  // a1 = 0.002 N/mm, a2 = 0.0023 N/mm²: at 20 mm, 0.04 + 0.92 N.
  EXPECT_NEAR(pre_puncture_force(p, 0.02), 0.002 * 20 + 0.0023 * 400, 1e-12);
}

TEST(NeedleModel, KarnoppHasItsFourBranches) {
  const KarnoppFriction k;     // Cp 0.121 mN/mm, Cn −0.117 mN/mm, bp 3.2, bn −1.6 mN s/mm², Δv 2 mm/s
  const double length = 0.03;  // 30 mm inserted
  // Slipping inward: 30 mm · (0.121 mN/mm + 3.2 mN s/mm² · 5 mm/s) = 30 · 16.121 mN.
  EXPECT_NEAR(karnopp_force(k, length, 0.005, 0.0), 30 * 16.121e-3, 1e-12);
  // Slipping outward: 30 mm · (−0.117 − 1.6 · 5) mN/mm, negative: it holds the needle back.
  EXPECT_NEAR(karnopp_force(k, length, -0.005, 0.0), 30 * -8.117e-3, 1e-12);
  // Stuck (|v| < Δv/2): what the shaft carried, within the static limits.
  EXPECT_NEAR(karnopp_force(k, length, 0.0005, 1e-3), 1e-3, 1e-15);
  EXPECT_NEAR(karnopp_force(k, length, -0.0005, 10.0), 30 * 0.121e-3, 1e-15);
  EXPECT_NEAR(karnopp_force(k, length, 0.0, -10.0), 30 * -0.117e-3, 1e-15);
  // No shaft inside, no friction.
  EXPECT_EQ(karnopp_force(k, 0.0, 0.01, 0.0), 0.0);
}

TEST(NeedleModel, RelaxationDecaysWithItsTimeConstant) {
  TissueNeedleParameters p;
  p.relaxation_time_s = 2.0;
  EXPECT_NEAR(relaxation_force(p, -2.5, 0.0), -2.5, 1e-15);
  EXPECT_NEAR(relaxation_force(p, -2.5, 2.0), -2.5 / std::exp(1.0), 1e-12);
}

TEST(NeedleModel, ExtremeParametersGiveFiniteForces) {
  TissueNeedleParameters p;
  p.fung_pre = {1e9, -1e300, 0.0, 1e300};
  EXPECT_TRUE(std::isfinite(pre_puncture_force(p, 1.0)));
  p.friction.damping_positive_n_s_per_m2 = 1e308;
  EXPECT_TRUE(std::isfinite(karnopp_force(p.friction, 10.0, 1e10, 0.0)));
}

TEST(NeedleModel, ValidationNamesTheAttribute) {
  TissueNeedleParameters p;
  p.capsule_m = -0.01;
  auto ok = validate(p, "needle tissue of body 'Liver'");
  ASSERT_FALSE(ok);
  EXPECT_NE(ok.error().message.find("capsule"), std::string::npos);
  EXPECT_NE(ok.error().message.find("Liver"), std::string::npos);
  p = {};
  p.fung_post.a_per_m = std::numeric_limits<double>::quiet_NaN();
  ok = validate(p, "needle tissue");
  ASSERT_FALSE(ok);
  EXPECT_NE(ok.error().message.find("fungPost"), std::string::npos);
  p = {};
  p.puncture_force_n = std::numeric_limits<double>::infinity();  // a file cannot hold it: refused
  ok = validate(p, "needle tissue");
  ASSERT_FALSE(ok);
  EXPECT_NE(ok.error().message.find("punctureForce"), std::string::npos);
  // Friction resists motion: Okamura's positive magnitudes on the negative side are refused
  // (they would push the hand out while it withdraws: energy into the user).
  p = {};
  p.friction.static_negative_n_per_m = 0.117;
  ok = validate(p, "needle tissue");
  ASSERT_FALSE(ok);
  EXPECT_NE(ok.error().message.find("Cn, bn <= 0"), std::string::npos);
  p = {};
  p.friction.damping_positive_n_s_per_m2 = -1.0;
  EXPECT_FALSE(validate(p, "needle tissue"));
}

TEST(NeedleModel, ThePrintedFormStartsEachPhaseFromAboutZero) {
  // The thesis' "+ b": f(d0) = F0 + 2b, which with Maurin's θ is 0.004 N and 0.01 N: both
  // phases start from about zero at their d0, and the post-puncture force is positive, rising
  // toward b = 1.7 N.
  TissueNeedleParameters p;
  p.fung_form = FungForm::kPrinted;
  EXPECT_NEAR(fung_force(p.fung_pre, 0.01145, p.fung_form), 0.2 + 2 * -0.098, 1e-12);
  EXPECT_NEAR(fung_force(p.fung_post, 0.01961, p.fung_form), -3.39 + 2 * 1.7, 1e-12);
  EXPECT_GT(post_puncture_force(p, 0.04, 0.01, 0.0), 0.7);
  EXPECT_NEAR(post_puncture_force(p, 1.0, 0.01, 0.0), 1.7, 1e-6);
  // The two forms differ by 2b everywhere.
  for (double d : {0.0, 0.01, 0.03}) {
    EXPECT_NEAR(fung_force(p.fung_pre, d, FungForm::kPrinted) - fung_force(p.fung_pre, d, FungForm::kIntegrated),
                2 * -0.098, 1e-12);
  }
}

TEST(NeedleModel, TheDefaultFormResistsInsertionAndThePressNeverPulls) {
  // The default is the form whose post-puncture force pushes the needle back (Maurin et al.
  // 2004 measured resisting forces that drop at each puncture and rise again).
  const TissueNeedleParameters p;
  EXPECT_EQ(p.fung_form, FungForm::kPrinted);
  for (double d = 0.0; d <= 0.08; d += 0.001) {
    EXPECT_GE(pre_puncture_force(p, d), 0.0) << "d = " << d;
    if (d >= p.capsule_m) {
      EXPECT_GT(post_puncture_force(p, d, 0.01, 0.0), 0.0) << "d = " << d;
    }
  }
  // Below d0 the printed fit is negative (-0.072 N at the surface): an intact capsule does not
  // pull, the force is zero there.
  EXPECT_LT(fung_force(p.fung_pre, 0.0, FungForm::kPrinted), -0.05);
  EXPECT_EQ(pre_puncture_force(p, 0.0), 0.0);
}

}  // namespace
}  // namespace hof::procedures
