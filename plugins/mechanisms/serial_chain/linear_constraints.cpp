// Parser of the textual linear design constraints (linear_constraints.hpp): a small recursive
// descent over one line; nothing here allocates per design (evaluate is a dot product).
#include "linear_constraints.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>

namespace hapsyn::plugins {

double LinearConstraint::evaluate(const double* design) const {
  double g = -constant;
  for (std::size_t k = 0; k < index.size(); ++k) g += coefficient[k] * design[index[k]];
  return g;
}

namespace {

// A linear expression: coefficients by component index, plus a constant.
struct Linear {
  std::map<int, double> terms;
  double constant = 0.0;
};

class ConstraintParser {
 public:
  ConstraintParser(const std::string& text, const std::vector<std::string>& components, const std::string& component,
                   const std::string& where)
      : text_(text), components_(components), component_(component), where_(where) {}

  // The comparisons of the line, each as (lhs, '<' for <= or '>' for >=, rhs).
  struct Comparison {
    Linear lhs, rhs;
    char direction;
    std::string written;
  };

  std::vector<Comparison> parse() {
    std::vector<Comparison> out;
    std::size_t start = skip();
    Linear lhs = expression();
    std::size_t lhs_start = start;
    while (true) {
      skip();
      if (pos_ >= text_.size()) break;
      char dir = 0;
      if (text_.compare(pos_, 2, "<=") == 0) dir = '<';
      else if (text_.compare(pos_, 2, ">=") == 0) dir = '>';
      else fail("expected '<=', '>=' or the end of the constraint");
      pos_ += 2;
      const std::size_t rhs_start = skip();
      Linear rhs = expression();
      std::string written = trim(text_.substr(lhs_start, pos_ - lhs_start));
      out.push_back({lhs, rhs, dir, written});
      lhs = rhs;
      lhs_start = rhs_start;
    }
    if (out.empty()) fail("a constraint needs '<=' or '>='");
    return out;
  }

  [[noreturn]] void fail(const std::string& rule) const {
    throw Error(component_, where_ + " = \"" + text_ + "\": " + rule + " (at character " + std::to_string(pos_ + 1) + ")");
  }

 private:
  static std::string trim(const std::string& s) {
    const auto b = s.find_first_not_of(' ');
    const auto e = s.find_last_not_of(' ');
    return b == std::string::npos ? "" : s.substr(b, e - b + 1);
  }
  std::size_t skip() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    return pos_;
  }
  bool at_name_start() const {
    return pos_ < text_.size() && (std::isalpha(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_');
  }
  bool at_number_start() const {
    return pos_ < text_.size() && (std::isdigit(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '.');
  }

  Linear expression() {
    Linear e;
    bool first = true;
    while (true) {
      skip();
      double sign = 1.0;
      if (pos_ < text_.size() && (text_[pos_] == '+' || text_[pos_] == '-')) {
        sign = text_[pos_] == '-' ? -1.0 : 1.0;
        ++pos_;
        skip();
      } else if (!first) {
        return e;
      }
      term(sign, e);
      first = false;
    }
  }

  void term(double sign, Linear& e) {
    double coefficient = sign;
    if (at_number_start()) {
      const double value = number();
      skip();
      if (pos_ < text_.size() && text_[pos_] == '*') {
        ++pos_;
        skip();
        coefficient *= value;
      } else {
        e.constant += sign * value;
        return;
      }
    }
    if (!at_name_start()) fail("expected a number or a design variable");
    e.terms[name_index()] += coefficient;
  }

  double number() {
    const char* begin = text_.c_str() + pos_;
    char* end = nullptr;
    const double value = std::strtod(begin, &end);
    if (end == begin) fail("expected a number");
    pos_ += static_cast<std::size_t>(end - begin);
    if (!std::isfinite(value)) fail("numbers must be finite");
    return value;
  }

  int name_index() {
    const std::size_t start = pos_;
    while (pos_ < text_.size() &&
           (std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_' || text_[pos_] == ':')) {
      ++pos_;
    }
    if (pos_ < text_.size() && text_[pos_] == '[') {
      const std::size_t close = text_.find(']', pos_);
      if (close == std::string::npos) fail("missing ']'");
      pos_ = close + 1;
    }
    const std::string name = text_.substr(start, pos_ - start);
    const auto it = std::find(components_.begin(), components_.end(), name);
    if (it == components_.end()) {
      std::string message = where_ + " = \"" + text_ + "\": unknown design variable '" + name + "'";
      const std::string near = nearest_name(name, components_);
      if (!near.empty()) message += " (did you mean '" + near + "'?)";
      std::string known;
      for (const std::string& c : components_) known += (known.empty() ? "" : ", ") + c;
      throw Error(component_, message + "; the mechanism's design variables are: " + known);
    }
    return static_cast<int>(it - components_.begin());
  }

  const std::string& text_;
  const std::vector<std::string>& components_;
  const std::string& component_;
  const std::string& where_;
  std::size_t pos_ = 0;
};

}  // namespace

std::vector<LinearConstraint> parse_linear_constraints(const std::vector<std::string>& texts,
                                                       const std::vector<std::string>& components,
                                                       const std::string& component, const std::string& option) {
  std::vector<LinearConstraint> out;
  for (std::size_t k = 0; k < texts.size(); ++k) {
    const std::string where = option + "[" + std::to_string(k) + "]";
    ConstraintParser parser(texts[k], components, component, where);
    const auto comparisons = parser.parse();
    for (std::size_t c = 0; c < comparisons.size(); ++c) {
      const auto& cmp = comparisons[c];
      // g = lhs - rhs for <=, rhs - lhs for >=.
      const double s = cmp.direction == '<' ? 1.0 : -1.0;
      std::map<int, double> terms = cmp.lhs.terms;
      for (const auto& [i, a] : cmp.rhs.terms) terms[i] -= a;
      LinearConstraint g;
      g.name = "constraints[" + std::to_string(k) + "]" + (comparisons.size() > 1 ? "." + std::to_string(c) : "");
      g.description = cmp.written;
      for (const auto& [i, a] : terms) {
        if (a == 0.0) continue;
        g.index.push_back(i);
        g.coefficient.push_back(s * a);
      }
      g.constant = s * (cmp.rhs.constant - cmp.lhs.constant);
      // Finite numbers can add up past the largest double: such a constraint would hold for no
      // design (or every one), so it is refused here rather than left to make a study infeasible.
      const std::string shown = where + " = \"" + texts[k] + "\": '" + cmp.written + "': ";
      if (!std::isfinite(g.constant)) {
        throw Error(component, shown + "its constant terms add up to " + std::to_string(g.constant) +
                                   ": they must sum to a finite number");
      }
      for (std::size_t t = 0; t < g.index.size(); ++t) {
        if (!std::isfinite(g.coefficient[t])) {
          throw Error(component, shown + "the coefficients of '" + components[static_cast<std::size_t>(g.index[t])] +
                                     "' add up to " + std::to_string(g.coefficient[t]) + ": they must sum to a finite number");
        }
      }
      if (g.index.empty()) {
        throw Error(component, where + " = \"" + texts[k] + "\": '" + cmp.written +
                                   "' has no design variable left (the terms cancel): it constrains nothing");
      }
      out.push_back(std::move(g));
    }
  }
  return out;
}

}  // namespace hapsyn::plugins
