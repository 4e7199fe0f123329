#pragma once
// The human of a scene that models one, as the page draws it: the scene's info "figure" (the
// rigid body) and the arm at one sample from the per-sample attribute it names.
#include <hapsyn/json.hpp>
#include <hapsyn/scene.hpp>

namespace hapsyn_cli {

/// The figure at `sample`: {"arm": [[x,y,z], ...] (the joints, shoulder to palm), "arm_joints":
/// their names, "body_lines", "head_centre", "head_radius"}, all in the scene frame; null when
/// the scene gives no info "figure" or no sample is drawn (sample < 0).
/// The contract for scenes (the human_arm scene follows it): info "figure" holds
/// "arm_attribute" (a per-sample attribute with 3 columns per joint), "arm_joints" (their
/// names), "body_lines" (polylines of [x,y,z] points), "head_centre" ([x,y,z]) and
/// "head_radius" (>= 0).
/// \throws hapsyn::Error("view", ...) naming the scene's info key, the value and the rule when
///         the figure does not follow that contract.
hapsyn::Json figure_json(const hapsyn::SampleSet& samples, int sample);

}  // namespace hapsyn_cli
