#pragma once
/// \file
/// Design variables and design spaces.
///
/// A mechanism declares its variables (VariableDecl); the problem file narrows them (bounds,
/// grid step, fixed value). Vector variables are flattened into scalar components named
/// "name[i]"; solvers only ever see a flat vector of the *free* (not fixed) components.
///
/// Resolution (build_design_space, below) turns a problem file's "design" section and the
/// mechanism's declarations into a DesignSpace; load_study calls it before anything expensive.
#include <hapsyn/json.hpp>

#include <Eigen/Core>
#include <string>
#include <vector>

namespace hapsyn {

/// Most grid points one design variable may have (its step against its range): beyond it a grid
/// is not searchable, and a tiny step (1e-20) would overflow the count.
constexpr long long kMaxGridAxisPoints = 1000000000LL;
/// Most points a whole design grid (the product over the free variables with a step) may have:
/// linear grid indices are long long.
constexpr long long kMaxGridPoints = 9000000000000000000LL;

/// A design variable as a mechanism declares it. Units are SI (m, rad, kg) unless `unit` says.
struct VariableDecl {
  std::string name;         ///< key in the problem file's "design" object, e.g. "l1"
  std::string description;  ///< one line for `hapsyn describe`
  std::string unit;         ///< e.g. "m"; "" for dimensionless or codes
  int size = 1;             ///< 1 for a scalar, n for a vector variable
  bool integer = false;     ///< integer-valued (joint size codes, gear codes)
  /// Default bounds (per component; a single entry is broadcast) used when the problem file
  /// does not narrow them.
  std::vector<double> default_lower, default_upper;
  /// Hard limits: bounds in the problem file must stay inside them (e.g. a length >= 0).
  std::vector<double> hard_lower, hard_upper;
};

/// A design constraint g(p) <= 0 as a mechanism declares it (Mechanism::constraints), evaluated
/// by Mechanism::evaluate_constraints.
struct ConstraintDecl {
  std::string name;
  std::string description;
};

/// One scalar component of the resolved design space.
struct DesignComponent {
  std::string name;      ///< "l1" or "l[2]"
  std::string variable;  ///< the variable it belongs to ("l")
  int index = 0;         ///< component index within the variable
  bool integer = false;
  double lower = 0.0, upper = 0.0;
  double step = 0.0;     ///< grid step; 0 = no grid (continuous)
  bool fixed = false;    ///< fixed to `lower` (== upper)
};

/// The resolved design space of a study (all components, fixed and free).
class DesignSpace {
 public:
  DesignSpace() = default;
  explicit DesignSpace(std::vector<DesignComponent> components);

  /// All components in declaration order (the layout of a full design vector).
  const std::vector<DesignComponent>& components() const { return components_; }
  std::size_t size() const { return components_.size(); }
  /// Indices (into components()) of the free components, in order: the solver's vector.
  const std::vector<int>& free_indices() const { return free_; }
  std::size_t free_size() const { return free_.size(); }

  /// Full design from a free vector (fixed components take their value).
  void expand(const double* free_values, double* full) const;
  Eigen::VectorXd expand(const Eigen::VectorXd& free_values) const;
  /// Number of grid points of free component k (requires a step): floor((upper-lower)/step)+1,
  /// with a relative tolerance so that an upper bound on the grid is included.
  /// \throws Error `("problem: design.<name>: ...")` above kMaxGridAxisPoints (build_design_space
  ///         refuses such steps first; this guards spaces built by hand).
  long long grid_count(std::size_t free_k) const;
  /// Grid value i of free component k: lower + i*step (clamped to upper).
  double grid_value(std::size_t free_k, long long i) const;
  /// Checks that every free component has a grid step and that the grid can be indexed, for a
  /// solver that searches the grid; returns the number of grid designs.
  /// \param component the solver, for the error ("grid", "culling")
  /// \param max_designs when > 0, the most grid designs the solver accepts (its `max_designs`
  ///        option): a search of more is refused at load, not discovered after days
  /// \throws Error `("<component>: design.<var> has no step: ...")` or when the grid exceeds
  ///         9e18 points, or `Error("<component>: the design grid has N designs (<axes>), more
  ///         than solver.options.max_designs = M; ...")` when it exceeds max_designs.
  long long check_grid(const std::string& component, double max_designs = 0.0) const;
  /// Grid counts of every free component (each needs a step).
  std::vector<long long> grid_counts() const;
  /// The free design of grid point `index` in the mixed-radix numbering of `counts` (the last
  /// component varies fastest): x_k = grid_value(k, i_k).
  void grid_point(long long index, const std::vector<long long>& counts, double* free_values) const;
  /// Index of a component by name ("l1", "l[2]"); -1 if absent.
  int find(const std::string& name) const;

 private:
  std::vector<DesignComponent> components_;
  std::vector<int> free_;
};

/// Resolves a problem file's "design" section against the mechanism's variables: every
/// declared variable becomes its components, each with the file's bounds (or the declared
/// defaults), grid step or fixed value. An entry is {"lower", "upper", "step"} or {"value"
/// (with optional "lower"/"upper")}; each of these is a number (broadcast to every component)
/// or an array with one number per component. A component whose bounds coincide is fixed.
/// \param design          the "design" object (variable name -> entry); may be empty
/// \param decls           the mechanism's variables, in declaration order
/// \param resolved_design out: the section as resolved (defaults filled in, units added), for
///                        result.json
/// \throws Error("problem", ...) naming the path ("design.l1.upper"), the value and the rule:
///         unknown variables or keys (with the nearest name), non-numbers, non-finite values,
///         wrong component counts, bounds outside the mechanism's hard limits, lower > upper,
///         a value outside its bounds, a step <= 0 or wider than the range, a step with a
///         value, non-integers for integer variables, a step that does not divide upper - lower
///         (relative tolerance 1e-9 on the step count; the message proposes the two nearest
///         dividing steps and the upper bound the step reaches), a step making more than
///         kMaxGridAxisPoints points, a grid (product over the variables with a step) of more
///         than kMaxGridPoints points.
DesignSpace build_design_space(const Json& design, const std::vector<VariableDecl>& decls, Json& resolved_design);

}  // namespace hapsyn
