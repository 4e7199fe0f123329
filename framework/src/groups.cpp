#include <hapsyn/error.hpp>
#include <hapsyn/internal/groups.hpp>
#include <hapsyn/output_files.hpp>
#include <hapsyn/internal/plot.hpp>

#include <boost/filesystem.hpp>

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace hapsyn {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void spread(GroupTable& t) {
  const Eigen::Index objectives = t.values.cols();
  t.mean = Eigen::VectorXd::Constant(objectives, kNaN);
  t.standard_deviation = Eigen::VectorXd::Constant(objectives, kNaN);
  for (Eigen::Index o = 0; o < objectives; ++o) {
    double sum = 0.0;
    int n = 0;
    for (Eigen::Index g = 0; g < t.values.rows(); ++g) {
      if (std::isfinite(t.values(g, o))) sum += t.values(g, o), ++n;
    }
    if (n == 0) continue;
    const double mean = sum / n;
    double squares = 0.0;
    for (Eigen::Index g = 0; g < t.values.rows(); ++g) {
      if (std::isfinite(t.values(g, o))) squares += (t.values(g, o) - mean) * (t.values(g, o) - mean);
    }
    t.mean(o) = mean;
    t.standard_deviation(o) = n > 1 ? std::sqrt(squares / (n - 1)) : 0.0;
  }
}

Json value_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
}  // namespace

std::vector<GroupTable> group_tables(const Problem& problem, const SampleRecords& records) {
  std::vector<GroupTable> tables;
  for (const SampleGrouping& g : problem.samples().groups) {
    GroupTable t;
    t.grouping = g.name;
    for (const Objective& o : problem.objectives()) t.objectives.push_back(o.name);
    t.labels = g.labels;
    t.samples.assign(g.labels.size(), 0);
    for (int label : g.of_sample) ++t.samples[static_cast<std::size_t>(label)];
    t.values = grouped_objective_values(problem, records, g.of_sample, t.samples);
    spread(t);
    tables.push_back(std::move(t));
  }
  return tables;
}

std::string groups_csv(const std::vector<GroupTable>& tables) {
  std::ostringstream csv;
  csv.precision(10);
  if (tables.empty()) return "";
  csv << "grouping,group,samples";
  for (const std::string& o : tables.front().objectives) csv << "," << o;
  csv << "\n";
  const auto cells = [&](const auto& row) {
    for (Eigen::Index o = 0; o < row.size(); ++o) {
      csv << ",";
      if (std::isfinite(row(o))) csv << row(o);
    }
    csv << "\n";
  };
  for (const GroupTable& t : tables) {
    for (std::size_t g = 0; g < t.labels.size(); ++g) {
      csv << t.grouping << "," << t.labels[g] << "," << t.samples[g];
      cells(t.values.row(static_cast<Eigen::Index>(g)));
    }
    csv << t.grouping << ",mean,";
    cells(t.mean);
    csv << t.grouping << ",std,";
    cells(t.standard_deviation);
  }
  return csv.str();
}

Json groups_json(const std::vector<GroupTable>& tables) {
  Json out = Json::object();
  for (const GroupTable& t : tables) {
    Json groups = Json::array(), mean = Json::object(), sd = Json::object();
    for (std::size_t g = 0; g < t.labels.size(); ++g) {
      Json values = Json::object();
      for (std::size_t o = 0; o < t.objectives.size(); ++o) {
        values[t.objectives[o]] = value_or_null(t.values(static_cast<Eigen::Index>(g), static_cast<Eigen::Index>(o)));
      }
      groups.push_back({{"label", t.labels[g]}, {"samples", t.samples[g]}, {"values", values}});
    }
    for (std::size_t o = 0; o < t.objectives.size(); ++o) {
      mean[t.objectives[o]] = value_or_null(t.mean(static_cast<Eigen::Index>(o)));
      sd[t.objectives[o]] = value_or_null(t.standard_deviation(static_cast<Eigen::Index>(o)));
    }
    out[t.grouping] = {{"objectives", t.objectives}, {"groups", groups}, {"mean", mean}, {"std", sd}};
  }
  return out;
}

namespace {
double number_or_nan(const Json& v) { return v.is_number() ? v.get<double>() : kNaN; }

std::string cell(double v, bool percent) {
  std::ostringstream c;
  if (!std::isfinite(v)) {
    c << "-";
  } else if (percent) {
    c << std::fixed << std::setprecision(1) << 100.0 * v << " %";
  } else {
    c << std::setprecision(6) << v;
  }
  return c.str();
}

void table_text(const std::string& grouping, const Json& table, std::ostream& s) {
  const std::vector<std::string> objectives = table["objectives"];
  // Shares (every value in [0, 1]) read best as percentages, like the paper's figures.
  std::vector<bool> percent(objectives.size(), true);
  std::size_t width = std::max<std::size_t>(grouping.size(), 4);
  for (const Json& g : table["groups"]) {
    width = std::max(width, g["label"].get<std::string>().size());
    for (std::size_t o = 0; o < objectives.size(); ++o) {
      const double v = number_or_nan(g["values"][objectives[o]]);
      if (std::isfinite(v) && (v < 0.0 || v > 1.0)) percent[o] = false;
    }
  }
  const auto row = [&](const std::string& label, const std::string& count, const Json& values) {
    s << "  " << std::left << std::setw(static_cast<int>(width)) << label << std::right << std::setw(8) << count;
    for (std::size_t o = 0; o < objectives.size(); ++o) {
      const int w = static_cast<int>(std::max<std::size_t>(objectives[o].size(), 8));
      s << "  " << std::setw(w) << (values.is_null() ? objectives[o] : cell(number_or_nan(values[objectives[o]]), percent[o]));
    }
    s << "\n";
  };
  row(grouping, "samples", Json(nullptr));
  for (const Json& g : table["groups"]) row(g["label"], std::to_string(g["samples"].get<long long>()), g["values"]);
  row("mean", "", table["mean"]);
  row("std", "", table["std"]);
}
}  // namespace

std::string groups_text(const Json& groups, std::size_t max_rows) {
  std::ostringstream s;
  for (auto it = groups.begin(); it != groups.end(); ++it) {
    if (it.value()["groups"].size() > max_rows) {
      s << "  " << it.key() << ": " << it.value()["groups"].size() << " groups (groups.csv)\n";
      continue;
    }
    table_text(it.key(), it.value(), s);
  }
  return s.str();
}

std::string plot_timeline(const Problem& problem, const SampleRecords& records, const std::string& grouping,
                          const std::string& label, const std::string& directory, std::string& message) {
  namespace fs = boost::filesystem;
  message.clear();
  const SampleSet& samples = problem.samples();
  const auto time = samples.attributes.find("time");
  const SampleGrouping* g = nullptr;
  for (const SampleGrouping& candidate : samples.groups) {
    if (candidate.name == grouping) g = &candidate;
  }
  if (time == samples.attributes.end() || !g) return "";
  int wanted = -1;
  std::string known;
  for (std::size_t k = 0; k < g->labels.size(); ++k) {
    if (g->labels[k] == label) wanted = static_cast<int>(k);
    known += (known.empty() ? "" : ", ") + g->labels[k];
  }
  if (wanted < 0) {
    throw Error("output", "timeline = \"" + label + "\": no " + grouping + " of that name (the scene has: " + known + ")");
  }
  // Every sample of the trajectory is its own group; the others share one group that is dropped.
  std::vector<int> members, group(static_cast<std::size_t>(samples.size()));
  for (int i = 0; i < samples.size(); ++i) {
    const bool in = g->of_sample[static_cast<std::size_t>(i)] == wanted;
    group[static_cast<std::size_t>(i)] = in ? static_cast<int>(members.size()) : -1;
    if (in) members.push_back(i);
  }
  const int others = static_cast<int>(members.size());
  for (int& k : group) k = k < 0 ? others : k;
  std::vector<int> counts(members.size() + 1, 1);
  counts.back() = samples.size() - others;
  const Eigen::MatrixXd values = grouped_objective_values(problem, records, group, counts);
  std::ostringstream dat;
  dat << "# time [s], then per objective its value on the sample alone (" << grouping << " " << label << ")\n";
  for (std::size_t k = 0; k < members.size(); ++k) {
    dat << time->second(members[k], 0);
    for (Eigen::Index o = 0; o < values.cols(); ++o) {
      const double v = values(static_cast<Eigen::Index>(k), o);
      dat << " " << (std::isfinite(v) ? v : kNaN);
    }
    dat << "\n";
  }
  const std::vector<Objective>& objectives = problem.objectives();
  const bool shares = ((values.array() >= 0.0 && values.array() <= 1.0) || values.array().isNaN()).all();
  // One panel per objective under a shared title, each named on its y axis (no key: one curve).
  std::ostringstream body;
  body << "set multiplot layout " << objectives.size() << ",1 title " << gnuplot_quote(grouping + " " + label)
       << "\nset xlabel 'time [s]'\n" << (shares ? "set yrange [-0.1:1.1]\n" : "") << "set grid\n";
  for (std::size_t o = 0; o < objectives.size(); ++o) {
    body << "set ylabel " << gnuplot_quote(objectives[o].name) << "\nplot 'timeline.dat' using 1:" << o + 2
         << " with steps lw 2 notitle\n";
  }
  body << "unset multiplot\n";
  write_file_atomically((fs::path(directory) / "timeline.dat").string(), dat.str());
  FigureStyle style;
  style.width = 1000;
  style.height = 160 + 140 * static_cast<int>(objectives.size());
  message = render_figure(directory, "timeline", "every objective along " + grouping + " " + label, style, body.str());
  return message.empty() ? "timeline.png" : "";
}

}  // namespace hapsyn
