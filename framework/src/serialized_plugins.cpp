#include "serialized_plugins.hpp"

#include <hapsyn/accel/metric_acceleration.hpp>
#include <hapsyn/options.hpp>

#include <mutex>

namespace hapsyn {

const char* to_string(ThreadSafety safety) {
  return safety == ThreadSafety::kSerialized ? "serialized" : "concurrent";
}

namespace {

using Lock = std::lock_guard<std::mutex>;

// The batch of a serialised metric, under the metric's lock.
class SerializedBatch final : public MetricAcceleration {
 public:
  SerializedBatch(const MetricAcceleration* const& inner, std::mutex& mutex) : inner_(inner), mutex_(mutex) {}
  int batch_size() const override {
    Lock lock(mutex_);
    return inner_->batch_size();
  }
  void local_batch(const SampleQuantities* const* q, int count, double* out) const override {
    Lock lock(mutex_);
    inner_->local_batch(q, count, out);
  }

 private:
  const MetricAcceleration* const& inner_;
  std::mutex& mutex_;
};

class SerializedMetric final : public Metric {
 public:
  explicit SerializedMetric(std::shared_ptr<Metric> inner) : inner_(std::move(inner)) {}
  void local(const SampleQuantities& q, double* out) const override {
    Lock lock(mutex_);
    inner_->local(q, out);
  }
  MetricSpecs specs() const override {
    Lock lock(mutex_);
    return inner_->specs();
  }
  std::vector<LocalValue> locals() const override {
    Lock lock(mutex_);
    return inner_->locals();
  }
  double combine(const double* reduced, int samples) const override {
    Lock lock(mutex_);
    return inner_->combine(reduced, samples);
  }
  Aggregation aggregation() const override {
    Lock lock(mutex_);
    return inner_->aggregation();
  }
  // Of the speed layer only the batch is forwarded (an interpreted metric's); block kernels and
  // bounds are for concurrent plugins.
  const MetricAcceleration* acceleration() const override {
    Lock lock(mutex_);
    inner_acceleration_ = inner_->acceleration();
    return inner_acceleration_ != nullptr ? &batch_ : nullptr;
  }

 private:
  std::shared_ptr<Metric> inner_;
  mutable std::mutex mutex_;
  mutable const MetricAcceleration* inner_acceleration_ = nullptr;
  SerializedBatch batch_{inner_acceleration_, mutex_};
};

// A model of a serialised mechanism shares the mechanism's lock: the plugin's code may keep
// state across its objects.
class SerializedModel final : public MechanismModel {
 public:
  SerializedModel(std::unique_ptr<const MechanismModel> inner, std::shared_ptr<std::mutex> mutex)
      : inner_(std::move(inner)), mutex_(std::move(mutex)) {}
  void solve(const double* pose, Needs needs, MechanismScratch& scratch, SampleQuantities& out) const override {
    Lock lock(*mutex_);
    inner_->solve(pose, needs, scratch, out);
  }

 private:
  std::unique_ptr<const MechanismModel> inner_;
  std::shared_ptr<std::mutex> mutex_;
};

class SerializedMechanism final : public Mechanism {
 public:
  explicit SerializedMechanism(std::shared_ptr<Mechanism> inner)
      : inner_(std::move(inner)), mutex_(std::make_shared<std::mutex>()) {}
  std::unique_ptr<const MechanismModel> build(const double* design) const override {
    std::unique_ptr<const MechanismModel> model;
    {
      Lock lock(*mutex_);
      model = inner_->build(design);
    }
    if (!model) return nullptr;
    return std::make_unique<SerializedModel>(std::move(model), mutex_);
  }
  // No speed layer (acceleration() is null): a model built in scratch could not carry the lock,
  // and block kernels are for concurrent plugins.
  std::vector<VariableDecl> variables() const override {
    Lock lock(*mutex_);
    return inner_->variables();
  }
  std::vector<ConstraintDecl> constraints() const override {
    Lock lock(*mutex_);
    return inner_->constraints();
  }
  void evaluate_constraints(const double* design, const SampleSet& scene, double* g) const override {
    Lock lock(*mutex_);
    inner_->evaluate_constraints(design, scene, g);
  }
  std::unique_ptr<MechanismScratch> make_scratch() const override {
    Lock lock(*mutex_);
    return inner_->make_scratch();
  }
  void check_scene(const SampleSet& scene) const override {
    Lock lock(*mutex_);
    inner_->check_scene(scene);
  }
  MechanismSpecs specs() const override {
    Lock lock(*mutex_);
    return inner_->specs();
  }

 private:
  std::shared_ptr<Mechanism> inner_;
  std::shared_ptr<std::mutex> mutex_;
};

}  // namespace

std::shared_ptr<Metric> serialized(std::shared_ptr<Metric> metric) {
  return std::make_shared<SerializedMetric>(std::move(metric));
}
std::shared_ptr<Mechanism> serialized(std::shared_ptr<Mechanism> mechanism) {
  return std::make_shared<SerializedMechanism>(std::move(mechanism));
}

}  // namespace hapsyn
