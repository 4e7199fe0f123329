// The cross-check of serial_chain against haptic6r on the paper's human-arm workspace (34,548
// poses; label slow: about a minute). See haptic6r_comparison.hpp.
#include "haptic6r_comparison.hpp"

#include <gtest/gtest.h>

using namespace hapsyn::plugins::test_support;

TEST(SerialChainPaperWorkspace, DhAndUrdfFormsAgreeWithTheClosedFormWhereBothPickTheSameConfiguration) {
#ifdef HAPSYN_HAVE_URDFDOM
  for (const char* form : {"dh", "urdf"}) {
#else
  for (const char* form : {"dh"}) {
#endif
    const auto options = std::string(form) == "dh" ? haptic6r_dh_options() : haptic6r_urdf_options();
    const Haptic6RComparison r = compare_with_haptic6r(options, "numerical", 24, paper_human_arm(), form);
    EXPECT_GE(r.same_share(), 0.999) << form;
  }
}
