// Self-test of the planar_2r example (a plain executable, registered with CTest; out of tree there
// is no hapsyn_add_test): the Jacobian against central finite differences of the forward
// kinematics, the inverse kinematics round trip on both branches, the classification, and the
// declared options. Prints one line per check; exits 1 when one fails.
#include "planar_2r.hpp"

#include <hapsyn/error.hpp>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

namespace {

using hapsyn::Json;
using hapsyn::SampleQuantities;
using hapsyn::SampleStatus;
using planar_2r_example::Planar2RModel;
using planar_2r_example::Planar2ROptions;

constexpr double kPi = 3.14159265358979323846;

int failures = 0;

std::string scientific(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1e", value);
  return text;
}

void check(bool ok, const std::string& what) {
  std::printf("%s: %s\n", ok ? "ok  " : "FAIL", what.c_str());
  if (!ok) ++failures;
}

Planar2ROptions options_of(const Json& options) { return hapsyn::make_options<Planar2ROptions>(options); }

// J at random configurations of random designs against central differences of forward() (step
// 1e-6 rad: truncation error ~ l h^2 / 6, rounding ~ eps l / h, both far below 1e-8 m/rad).
void jacobian_matches_finite_differences() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> length(0.05, 0.5), angle(-3.1, 3.1);
  double worst = 0.0;
  for (int trial = 0; trial < 1000; ++trial) {
    const Planar2RModel model(length(rng), length(rng), options_of(Json::object()));
    const double q[2] = {angle(rng), angle(rng)};
    hapsyn::TaskJointMatrix j;
    model.jacobian(q[0], q[1], j);
    const double h = 1e-6;
    for (int c = 0; c < 2; ++c) {
      double plus[2], minus[2];
      const double dq1 = c == 0 ? h : 0.0, dq2 = c == 1 ? h : 0.0;
      model.forward(q[0] + dq1, q[1] + dq2, plus);
      model.forward(q[0] - dq1, q[1] - dq2, minus);
      for (int r = 0; r < 2; ++r) worst = std::max(worst, std::abs((plus[r] - minus[r]) / (2 * h) - j(r, c)));
    }
  }
  check(worst < 1e-8, "Jacobian = central finite differences of the forward kinematics (max error " +
                          scientific(worst) + " m/rad)");
}

// forward(solve(p)) = p, and solve(forward(q)) = q on the branch of q's sign.
void inverse_kinematics_round_trips() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> length(0.05, 0.5), q1s(-3.1, 3.1), q2s(0.05, 3.09);
  double worst_pose = 0.0, worst_q = 0.0;
  for (const char* sign : {"positive", "negative"}) {
    const double s = std::string(sign) == "negative" ? -1.0 : 1.0;
    for (int trial = 0; trial < 1000; ++trial) {
      const Planar2RModel model(length(rng), length(rng), options_of(Json{{"q2_sign", sign}}));
      const double q1 = q1s(rng), q2 = s * q2s(rng);
      double p[2], back[2];
      model.forward(q1, q2, p);
      hapsyn::MechanismScratch scratch;
      SampleQuantities out;
      model.solve(p, hapsyn::kNeedJacobian, scratch, out);
      if (out.status != SampleStatus::kReachable) {
        check(false, "a forward-kinematics pose is reachable");
        return;
      }
      model.forward(out.q(0), out.q(1), back);
      worst_pose = std::max({worst_pose, std::abs(back[0] - p[0]), std::abs(back[1] - p[1])});
      worst_q = std::max({worst_q, std::abs(std::remainder(out.q(0) - q1, 2 * kPi)), std::abs(out.q(1) - q2)});
    }
  }
  check(worst_pose < 1e-12, "forward(inverse(p)) = p on both branches (max error " + scientific(worst_pose) + " m)");
  check(worst_q < 1e-9, "inverse(forward(q)) = q on q2's branch (max error " + scientific(worst_q) + " rad)");
}

SampleStatus status_at(const Planar2RModel& model, double x, double y) {
  hapsyn::MechanismScratch scratch;
  SampleQuantities out;
  const double p[2] = {x, y};
  model.solve(p, hapsyn::kNeedPose, scratch, out);
  return out.status;
}

void classification() {
  const Planar2RModel model(0.3, 0.2, options_of(Json::object()));
  check(status_at(model, 0.3, 0.2) == SampleStatus::kReachable, "inside the annulus: reachable");
  check(status_at(model, 0.5 + 1e-6, 0.0) == SampleStatus::kUnreachable, "beyond l1 + l2: unreachable");
  check(status_at(model, 0.1 - 1e-6, 0.0) == SampleStatus::kUnreachable, "inside |l1 - l2|: unreachable");
  check(status_at(model, 0.0, 0.5) == SampleStatus::kSingular, "stretched (|p| = l1 + l2): singular");
  check(status_at(model, 0.1, 0.0) == SampleStatus::kSingular, "folded (|p| = |l1 - l2|): singular");
}

void options_are_declared() {
  const Planar2ROptions defaults = hapsyn::default_options<Planar2ROptions>();
  check(defaults.q2_sign == "positive" && defaults.singularity_tolerance == 1e-6, "declared defaults");
  std::string message;
  try {
    options_of(Json{{"q2_sign", "up"}});
  } catch (const hapsyn::Error& e) {
    message = e.what();
  }
  check(message == "problem: options.q2_sign = \"up\": must be one of \"positive\", \"negative\"",
        "an undeclared branch is refused: " + message);
  try {
    const Planar2RModel model(0.0, 0.2, defaults);
    message = "no error";
  } catch (const hapsyn::Error& e) {
    message = e.what();
  }
  check(message == "planar_2r: design l1 = 0.0: must be finite and > 0", "a zero length is refused: " + message);
}

}  // namespace

int main() {
  jacobian_matches_finite_differences();
  inverse_kinematics_round_trips();
  classification();
  options_are_declared();
  std::printf("planar_2r_test: %s\n", failures == 0 ? "all checks passed" : "FAILED");
  return failures == 0 ? 0 : 1;
}
