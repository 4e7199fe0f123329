#include <hapsyn/error.hpp>
#include <hapsyn/internal/maps.hpp>
#include <hapsyn/internal/plot.hpp>
#include <hapsyn/output_files.hpp>

#include <boost/filesystem.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

namespace hapsyn {

std::vector<std::string> local_columns(const Problem& problem) {
  std::vector<std::string> names;
  for (const MetricEntry& m : problem.metrics()) {
    for (const LocalValue& l : m.metric->locals()) names.push_back(m.plugin + "." + l.name);
  }
  // A metric used by several objectives (coverage with other options) repeats its names: each
  // occurrence gets its index among the equal names, so every column can be selected by name.
  std::map<std::string, int> count, seen;
  for (const std::string& n : names) ++count[n];
  for (std::string& n : names) {
    if (count[n] > 1) n += "[" + std::to_string(seen[n]++) + "]";
  }
  return names;
}

std::string samples_csv(const Problem& problem, const SampleRecords& records) {
  std::ostringstream csv;
  csv.precision(10);
  const SampleSet& samples = problem.samples();
  csv << "sample";
  for (int c = 0; c < samples.dimension(); ++c) {
    csv << "," << (static_cast<std::size_t>(c) < samples.coordinates.size() ? samples.coordinates[static_cast<std::size_t>(c)] : "c" + std::to_string(c));
  }
  const bool weighted = !samples.weights.empty();
  if (weighted) csv << ",weight";
  csv << ",status";
  for (const std::string& column : local_columns(problem)) csv << "," << column;
  csv << "\n";
  for (int i = 0; i < samples.size(); ++i) {
    csv << i;
    for (int c = 0; c < samples.dimension(); ++c) csv << "," << samples.poses(i, c);
    if (weighted) csv << "," << samples.weights[static_cast<std::size_t>(i)];
    csv << "," << records.status[static_cast<std::size_t>(i)];
    for (Eigen::Index c = 0; c < records.locals.cols(); ++c) {
      csv << ",";
      if (records.has_locals[static_cast<std::size_t>(i)]) csv << records.locals(i, c);
    }
    csv << "\n";
  }
  return csv.str();
}

Eigen::MatrixXd grouped_objective_values(const Problem& problem, const SampleRecords& records,
                                         const std::vector<int>& group, const std::vector<int>& samples_per_group) {
  // Per group and metric: reduce the locals as the evaluator does, then combine.
  const SampleSet& samples = problem.samples();
  const std::size_t groups = samples_per_group.size();
  std::vector<int> offset;
  std::vector<Reduction> reduction;
  for (const MetricEntry& m : problem.metrics()) {
    offset.push_back(static_cast<int>(reduction.size()));
    for (const LocalValue& l : m.metric->locals()) reduction.push_back(l.reduction);
  }
  const std::size_t total = reduction.size();
  std::vector<double> reduced(groups * total);
  for (std::size_t g = 0; g < groups; ++g) {
    for (std::size_t k = 0; k < total; ++k) {
      reduced[g * total + k] = reduction[k] == Reduction::kSum   ? 0.0
                               : reduction[k] == Reduction::kMin ? std::numeric_limits<double>::infinity()
                                                                 : -std::numeric_limits<double>::infinity();
    }
  }
  // With weights, a group's sum-reduced locals are scaled by w_i n_g / W_g (n_g samples, W_g
  // their weight): the group's weighted mean, whether combine() divides by the sample count or
  // by another sum. A group whose weights are equal, or all 0, is reduced unweighted.
  std::vector<double> scale(static_cast<std::size_t>(samples.size()), 1.0);
  if (!samples.weights.empty()) {
    std::vector<double> weight_sum(groups, 0.0), first(groups, -1.0);
    std::vector<char> equal(groups, 1);
    for (std::size_t i = 0; i < scale.size(); ++i) {
      const std::size_t g = static_cast<std::size_t>(group[i]);
      const double w = samples.weights[i];
      if (first[g] < 0.0) first[g] = w;
      equal[g] = equal[g] && w == first[g];
      weight_sum[g] += w;
    }
    for (std::size_t i = 0; i < scale.size(); ++i) {
      const std::size_t g = static_cast<std::size_t>(group[i]);
      if (!equal[g] && weight_sum[g] > 0.0) scale[i] = samples.weights[i] * samples_per_group[g] / weight_sum[g];
    }
  }
  std::vector<char> undefined(groups * problem.metrics().size(), 0);
  for (int i = 0; i < samples.size(); ++i) {
    const std::size_t g = static_cast<std::size_t>(group[static_cast<std::size_t>(i)]);
    if (!records.has_locals[static_cast<std::size_t>(i)]) {
      for (std::size_t m = 0; m < problem.metrics().size(); ++m) undefined[g * problem.metrics().size() + m] = 1;
      continue;
    }
    for (std::size_t k = 0; k < total; ++k) {
      double& r = reduced[g * total + k];
      const double v = records.locals(i, static_cast<Eigen::Index>(k));
      r = reduction[k] == Reduction::kSum ? r + v * scale[static_cast<std::size_t>(i)] : reduction[k] == Reduction::kMin ? std::min(r, v) : std::max(r, v);
    }
  }
  Eigen::MatrixXd values(static_cast<Eigen::Index>(groups), static_cast<Eigen::Index>(problem.objectives().size()));
  for (std::size_t g = 0; g < groups; ++g) {
    for (std::size_t o = 0; o < problem.objectives().size(); ++o) {
      const std::size_t m = static_cast<std::size_t>(problem.objectives()[o].metric);
      const bool bad = undefined[g * problem.metrics().size() + m] != 0;
      values(static_cast<Eigen::Index>(g), static_cast<Eigen::Index>(o)) =
          bad ? std::numeric_limits<double>::quiet_NaN()
              : problem.metrics()[m].metric->combine(&reduced[g * total + static_cast<std::size_t>(offset[m])],
                                                     samples_per_group[g]);
    }
  }
  return values;
}

PositionMaps position_maps(const Problem& problem, const SampleRecords& records) {
  const SampleSet& samples = problem.samples();
  PositionMaps maps;
  for (const Objective& o : problem.objectives()) maps.objectives.push_back(o.name);

  // Which coordinates are the position: those named x, y, z.
  std::array<int, 3> axis{-1, -1, -1};
  for (std::size_t c = 0; c < samples.coordinates.size(); ++c) {
    const std::string& name = samples.coordinates[c];
    if (name == "x") axis[0] = static_cast<int>(c);
    if (name == "y") axis[1] = static_cast<int>(c);
    if (name == "z") axis[2] = static_cast<int>(c);
  }
  const bool is_lattice = samples.lattice.has_value();
  if (is_lattice) {
    maps.lattice_per_axis = samples.lattice->per_axis;
    maps.lattice_step = samples.lattice->step;
    maps.lattice_to_poses = samples.lattice->lattice_to_poses;
    maps.lattice_origin = samples.lattice->origin;
    maps.lattice_frame = samples.lattice->frame;
  }

  // Group samples by position, in order of first appearance (deterministic).
  std::vector<int> group(static_cast<std::size_t>(samples.size()));
  std::map<std::tuple<double, double, double>, int> by_position;
  std::map<long long, int> by_lattice;
  for (int i = 0; i < samples.size(); ++i) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int a = 0; a < 3; ++a) {
      if (axis[static_cast<std::size_t>(a)] >= 0) p[a] = samples.poses(i, axis[static_cast<std::size_t>(a)]);
    }
    int g;
    if (is_lattice) {
      const long long key = samples.lattice->index_of_sample[static_cast<std::size_t>(i)];
      const auto [it, inserted] = by_lattice.emplace(key, static_cast<int>(maps.position.size()));
      g = it->second;
      if (inserted) maps.lattice_index.push_back(static_cast<int>(key));
    } else {
      const auto [it, inserted] = by_position.emplace(std::make_tuple(p[0], p[1], p[2]), static_cast<int>(maps.position.size()));
      g = it->second;
      if (inserted) maps.lattice_index.push_back(-1);
    }
    if (g == static_cast<int>(maps.position.size())) {
      maps.position.push_back(p);
      maps.samples.push_back(0);
    }
    group[static_cast<std::size_t>(i)] = g;
    ++maps.samples[static_cast<std::size_t>(g)];
  }

  maps.values = grouped_objective_values(problem, records, group, maps.samples);
  return maps;
}

std::string maps_csv(const PositionMaps& maps) {
  std::ostringstream csv;
  csv.precision(10);
  csv << "position,x,y,z,samples";
  if (maps.lattice_per_axis > 0) csv << ",lattice_index";
  for (const std::string& name : maps.objectives) csv << "," << name;
  csv << "\n";
  for (std::size_t g = 0; g < maps.position.size(); ++g) {
    csv << g << "," << maps.position[g][0] << "," << maps.position[g][1] << "," << maps.position[g][2] << ","
        << maps.samples[g];
    if (maps.lattice_per_axis > 0) csv << "," << maps.lattice_index[g];
    for (Eigen::Index o = 0; o < maps.values.cols(); ++o) {
      const double v = maps.values(static_cast<Eigen::Index>(g), o);
      csv << ",";
      if (std::isfinite(v)) csv << v;
    }
    csv << "\n";
  }
  return csv.str();
}

namespace {
std::string file_safe(const std::string& name) {
  std::string s = name;
  for (char& c : s) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') c = '_';
  }
  return s;
}
}  // namespace

namespace {

// The z layers of scattered positions, highest first: each distinct z (a box or a point list
// in layers) when there are at most kMaxLayerPanels, else kMaxLayerPanels equal bands. One
// layer (a planar scene) is the whole map.
constexpr std::size_t kMaxLayerPanels = 12;

struct Layer {
  double low, high;  // z within [low, high]
  std::string title;
};

std::vector<Layer> z_layers(const std::vector<Eigen::Vector3d>& positions) {
  std::set<double> zs;
  for (const Eigen::Vector3d& p : positions) zs.insert(p.z());
  std::vector<Layer> layers;
  const auto shown = [](double z) {
    std::ostringstream s;
    s.precision(4);
    s << z;
    return s.str();
  };
  if (zs.size() <= kMaxLayerPanels) {
    for (auto it = zs.rbegin(); it != zs.rend(); ++it) layers.push_back({*it, *it, "z = " + shown(*it)});
    return layers;
  }
  const double lo = *zs.begin(), hi = *zs.rbegin(), width = (hi - lo) / static_cast<double>(kMaxLayerPanels);
  for (std::size_t k = kMaxLayerPanels; k-- > 0;) {
    const double a = lo + width * static_cast<double>(k), b = k + 1 == kMaxLayerPanels ? hi : a + width;
    layers.push_back({a, b, "z in [" + shown(a) + ", " + shown(b) + (k + 1 == kMaxLayerPanels ? "]" : ")")});
  }
  return layers;
}

// map_<objective> of a scene without a lattice: an x-y scatter per z layer (a 3-D box or point
// list once overprinted its layers in one x-y plot, the z ignored).
std::string plot_scattered_slices(const PositionMaps& maps, Eigen::Index o, const std::string& directory,
                                  const std::string& name, double colour_max) {
  namespace fs = boost::filesystem;
  const std::string& objective = maps.objectives[static_cast<std::size_t>(o)];
  const std::vector<Layer> layers = z_layers(maps.position);
  std::ostringstream data, script;
  data << "# x y " << objective << ", one block per z layer (highest first; gnuplot index)\n";
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const bool last_band = l == 0;  // bands are half-open except the highest
    data << (l ? "\n\n" : "") << "# " << layers[l].title << "\n";
    for (std::size_t g = 0; g < maps.position.size(); ++g) {
      const double z = maps.position[g].z();
      if (z < layers[l].low || z > layers[l].high || (!last_band && z == layers[l].high && layers[l].low != layers[l].high)) {
        continue;
      }
      const double v = maps.values(static_cast<Eigen::Index>(g), o);
      data << maps.position[g][0] << " " << maps.position[g][1] << " ";
      if (std::isfinite(v)) {
        data << v << "\n";
      } else {
        data << "?\n";
      }
    }
  }
  const std::size_t panels = layers.size();
  const std::size_t columns = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(panels))));
  const std::size_t rows = (panels + columns - 1) / columns;
  const std::string title = objective + (panels > 1 ? " per position, by height z" : " per position");
  script << "set datafile missing '?'\nset size ratio -1\n"
         << "set palette rgbformulae 33,13,10\nset cbrange [0:" << colour_max << "]\n"
         << "set xlabel 'x [m]'\nset ylabel 'y [m]'\nset cblabel " << gnuplot_quote(objective) << "\n"
         << "set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05\nset xtics rotate by 45 right\n";
  if (panels > 1) script << "set multiplot layout " << rows << "," << columns << " title " << gnuplot_quote(title) << "\n";
  for (std::size_t l = 0; l < panels; ++l) {
    script << "set title " << gnuplot_quote(panels > 1 ? layers[l].title : title) << "\n"
           << "plot " << gnuplot_quote(name + ".dat") << " index " << l << " using 1:2:3 with points pt 5 ps 0.6 palette\n";
  }
  if (panels > 1) script << "unset multiplot\n";
  write_file_atomically((fs::path(directory) / (name + ".dat")).string(), data.str());
  FigureStyle style;
  style.width = static_cast<int>(420 * columns + 120);
  style.height = static_cast<int>(380 * rows + 60);
  style.font_size = 10;
  return render_figure(directory, name, title, style, script.str());
}

}  // namespace

std::vector<std::string> plot_maps(const PositionMaps& maps, const std::string& directory, std::string& message) {
  namespace fs = boost::filesystem;
  std::vector<std::string> plotted;
  message.clear();
  for (Eigen::Index o = 0; o < maps.values.cols(); ++o) {
    const std::string& objective = maps.objectives[static_cast<std::size_t>(o)];
    const std::string name = "map_" + file_safe(objective);
    double top = 0.0;
    for (Eigen::Index g = 0; g < maps.values.rows(); ++g) {
      if (std::isfinite(maps.values(g, o))) top = std::max(top, maps.values(g, o));
    }
    const double colour_max = top <= 1.0 ? 1.0 : top;
    std::string why;
    if (maps.lattice_per_axis > 0) {
      LatticeField field;
      field.per_axis = maps.lattice_per_axis;
      field.step = maps.lattice_step;
      field.lattice_to_plot = maps.lattice_to_poses;
      field.origin = maps.lattice_origin;
      field.lattice_frame = maps.lattice_frame;
      const std::size_t n = static_cast<std::size_t>(maps.lattice_per_axis);
      field.values.assign(n * n * n, std::numeric_limits<double>::quiet_NaN());
      for (std::size_t g = 0; g < maps.position.size(); ++g) {
        const std::size_t index = static_cast<std::size_t>(maps.lattice_index[g]);
        if (index < field.values.size()) field.values[index] = maps.values(static_cast<Eigen::Index>(g), o);
      }
      field.value_label = objective;
      why = plot_lattice_slices(directory, name, objective + " per position (positions without human poses blank)",
                                field, colour_max);
    } else {
      why = plot_scattered_slices(maps, o, directory, name, colour_max);
    }
    if (why.empty()) {
      plotted.push_back(name + ".png");
    } else if (message.empty()) {
      message = why;
    }
  }
  return plotted;
}

}  // namespace hapsyn
