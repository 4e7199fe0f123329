#pragma once
/// \file
/// Design constraints written as text in a problem file: linear inequalities over named design
/// components, optionally chained, e.g.
///   "l1 + l2 <= 0.9"
///   "2*l1 - 0.5*l3 >= 0.1"
///   "size[0] >= size[1] >= size[2]"          (a monotone sequence: one constraint per '>=')
/// Grammar: expression (('<=' | '>=') expression)+; an expression is a sum of terms
/// [+|-] [number '*'] name | [+|-] number. A name is a design component ("l1", "size[2]",
/// "shoulder_lift_joint:z"): letters, digits, '_' and ':', starting with a letter or '_',
/// optionally followed by "[k]". Every comparison becomes one g(p) = a.p - b <= 0.
#include <string>
#include <vector>

namespace hapsyn::plugins {

/// One linear constraint g(p) = sum_k coefficient_k * p[index_k] - constant <= 0.
struct LinearConstraint {
  std::string name;         ///< "constraints[0]" or "constraints[0].1" for the 2nd comparison of a chain
  std::string description;  ///< the comparison as written, e.g. "l1 + l2 <= 0.9"
  std::vector<int> index;   ///< indices into the full design vector
  std::vector<double> coefficient;
  double constant = 0.0;

  /// g(p) for a full design vector.
  double evaluate(const double* design) const;
};

/// Parses the constraints of a problem file.
/// \param texts      the option's strings
/// \param components the full design vector's component names, in order
/// \param component  the plugin, for errors ("serial_chain")
/// \param option     the option's path, for errors ("options.constraints")
/// \throws Error("<component>", "<option>[k] = \"<text>\": <rule>") for a syntax error (with
///         the character position), an unknown name (did-you-mean and the list of names), a
///         comparison without a variable, or a non-finite number.
std::vector<LinearConstraint> parse_linear_constraints(const std::vector<std::string>& texts,
                                                       const std::vector<std::string>& components,
                                                       const std::string& component, const std::string& option);

}  // namespace hapsyn::plugins
