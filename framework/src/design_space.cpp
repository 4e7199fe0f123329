#include <hapsyn/design_space.hpp>
#include <hapsyn/error.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace hapsyn {

DesignSpace::DesignSpace(std::vector<DesignComponent> components) : components_(std::move(components)) {
  for (std::size_t i = 0; i < components_.size(); ++i) {
    if (!components_[i].fixed) free_.push_back(static_cast<int>(i));
  }
}

void DesignSpace::expand(const double* free_values, double* full) const {
  std::size_t k = 0;
  for (std::size_t i = 0; i < components_.size(); ++i) {
    full[i] = components_[i].fixed ? components_[i].lower : free_values[k++];
  }
}

Eigen::VectorXd DesignSpace::expand(const Eigen::VectorXd& free_values) const {
  assert(static_cast<std::size_t>(free_values.size()) == free_.size());
  Eigen::VectorXd full(static_cast<Eigen::Index>(components_.size()));
  expand(free_values.data(), full.data());
  return full;
}

long long DesignSpace::grid_count(std::size_t free_k) const {
  const DesignComponent& c = components_[static_cast<std::size_t>(free_[free_k])];
  assert(c.step > 0.0);
  // The tolerance keeps an upper bound that lies on the grid (0.3 = 0.01 + 29 * 0.01) on it,
  // despite (upper - lower) / step evaluating to 28.999999999999996.
  const double n = (c.upper - c.lower) / c.step;
  return static_cast<long long>(std::floor(n + 1e-9 * std::max(1.0, n))) + 1;
}

double DesignSpace::grid_value(std::size_t free_k, long long i) const {
  const DesignComponent& c = components_[static_cast<std::size_t>(free_[free_k])];
  // lower + i * step, not repeated addition, so that every grid value is reproducible.
  return std::min(c.upper, c.lower + static_cast<double>(i) * c.step);
}

long long DesignSpace::check_grid(const std::string& component) const {
  long double total = 1;
  for (std::size_t k = 0; k < free_.size(); ++k) {
    const DesignComponent& c = components_[static_cast<std::size_t>(free_[k])];
    if (!(c.step > 0.0)) {
      throw Error(component, "design." + c.variable + " has no step: searching the design grid needs a \"step\" for "
                             "every free design variable (or a \"value\" to fix it)");
    }
    total *= static_cast<long double>(grid_count(k));
  }
  // Linear grid indices are long long: refuse what they cannot number.
  if (total > 9e18L) throw Error(component, "the design grid has more than 9e18 points; use larger steps");
  return static_cast<long long>(total);
}

std::vector<long long> DesignSpace::grid_counts() const {
  std::vector<long long> counts(free_.size());
  for (std::size_t k = 0; k < counts.size(); ++k) counts[k] = grid_count(k);
  return counts;
}

void DesignSpace::grid_point(long long index, const std::vector<long long>& counts, double* free_values) const {
  for (std::size_t k = counts.size(); k-- > 0;) {
    free_values[k] = grid_value(k, index % counts[k]);
    index /= counts[k];
  }
}

int DesignSpace::find(const std::string& name) const {
  for (std::size_t i = 0; i < components_.size(); ++i) {
    if (components_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace hapsyn
