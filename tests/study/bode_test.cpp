// The Bode section's verdict on fractionality (study/bode.hpp) follows its stated rule.
#include <gtest/gtest.h>

#include <complex>

#include "study/bode.hpp"

namespace canalsim::study {
namespace {

BodeSection section(double lambda, double error, double integer_error) {
  BodeSection b;
  b.experiment = "op9";
  b.operating_opening_mm = 30.0;
  b.pde_fit.order = lambda;
  b.pde_fit.rms_relative_error = error;
  b.pde_fit.integer_rms_relative_error = integer_error;
  return b;
}

TEST(BodeSection, TheSentenceFollowsTheFractionalityRule) {
  EXPECT_NE(fractionality_sentence(section(0.5, 0.03, 0.09)).find("is fractional in the PRBS band with λ = 0.50"),
            std::string::npos);
  // λ < 0.9 but no better than λ = 1: first order.
  EXPECT_NE(fractionality_sentence(section(0.8, 0.05, 0.06)).find("is a first-order lag"), std::string::npos);
  EXPECT_NE(fractionality_sentence(section(0.97, 0.02, 0.02)).find("is a first-order lag"), std::string::npos);
  // Nothing within 10 %.
  EXPECT_NE(fractionality_sentence(section(0.7, 0.28, 0.29)).find("is not a first-order lag of any order"),
            std::string::npos);
}

TEST(BodeSection, ThePageDrawsGainAndPhaseForEachOperatingPoint) {
  BodeSection b = section(0.5, 0.03, 0.09);
  b.experiment = "op<1>";
  b.band = {0.1, 10.0};
  for (double w : {0.1, 1.0, 10.0}) {
    b.omega.push_back(w);
    b.pde.push_back(1.0 / std::complex<double>(1.0, w));
    b.liom.push_back(0.9 / std::complex<double>(1.0, w));
    b.lfom.push_back(1.1 / std::complex<double>(1.0, w));
  }
  b.sentence = fractionality_sentence(b);
  const std::string page = bode_html({b, b});
  std::size_t svgs = 0;
  for (auto at = page.find("<svg"); at != std::string::npos; at = page.find("<svg", at + 1)) ++svgs;
  EXPECT_EQ(svgs, 2u);  // one figure per section: gain above phase on one ω axis
  for (const char* text : {">gain [dB]<", ">phase [deg]<", ">ω [rad/s]<", ">PDE (linearised pool)<", ">LIOM fitted to the recording<",
                           ">LFOM fitted to the recording<", ">0.1<", ">10<"}) {
    EXPECT_NE(page.find(text), std::string::npos) << text;
  }
  EXPECT_EQ(bode_figures({b}).front().name, "bode_op_1_");
  EXPECT_NE(page.find("op&lt;1&gt;"), std::string::npos);
  EXPECT_EQ(page.find("nan"), std::string::npos);
  EXPECT_NE(bode_markdown({b}).find("| 1 | 0.707 | 0.636 | 0.778 | -45 | -45 | -45 |"), std::string::npos)
      << bode_markdown({b});
  // report.html's Bode section: the same plots, one level down in the heading hierarchy, no page
  // wrapper of its own.
  const std::string part = bode_html_section({b});
  EXPECT_NE(part.find("<h2 id=\"bode\">Bode"), std::string::npos);
  EXPECT_NE(part.find("<h3>op&lt;1&gt;"), std::string::npos);
  EXPECT_NE(part.find("<svg"), std::string::npos);
  EXPECT_EQ(part.find("<body"), std::string::npos);
}

}  // namespace
}  // namespace canalsim::study
