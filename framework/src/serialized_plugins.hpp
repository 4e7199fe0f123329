#pragma once
// Acting on ThreadSafety::kSerialized (hapsyn/options.hpp): wrappers that forward every call of
// a metric or mechanism (and of the models it builds) under one lock per plugin object, so that
// the evaluator may call them from any number of threads. Internal to the registry.
#include <hapsyn/mechanism.hpp>
#include <hapsyn/metric.hpp>
#include <hapsyn/scene.hpp>
#include <hapsyn/solver.hpp>

#include <memory>

namespace hapsyn {

std::shared_ptr<Metric> serialized(std::shared_ptr<Metric> metric);
std::shared_ptr<Mechanism> serialized(std::shared_ptr<Mechanism> mechanism);
// Scenes build once from one thread and solvers run once per study: nothing to serialise.
inline std::shared_ptr<Scene> serialized(std::shared_ptr<Scene> scene) { return scene; }
inline std::shared_ptr<Solver> serialized(std::shared_ptr<Solver> solver) { return solver; }

}  // namespace hapsyn
