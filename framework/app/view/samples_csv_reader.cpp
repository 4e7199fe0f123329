#include "samples_csv_reader.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/read_file.hpp>

#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <vector>

namespace hapsyn_cli {
namespace {

constexpr std::uint64_t kMaxSamplesCsvBytes = std::uint64_t{4} << 30;

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

}  // namespace

hapsyn::SampleRecords read_samples_csv(const std::string& file, const hapsyn::Problem& problem) {
  std::istringstream in(hapsyn::read_regular_file(file, "view", "samples.csv", kMaxSamplesCsvBytes));
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split_csv_line(line);
  const std::vector<std::string> locals = hapsyn::local_columns(problem);
  auto column = [&](const std::string& name) {
    for (std::size_t c = 0; c < header.size(); ++c) {
      if (header[c] == name) return c;
    }
    throw hapsyn::Error("view", file + ": no column \"" + name + "\" (the study's columns are those hapsyn run writes)");
  };
  const std::size_t status = column("status");
  std::vector<std::size_t> local_at;
  for (const std::string& l : locals) local_at.push_back(column(l));
  const int n = problem.samples().size();
  hapsyn::SampleRecords records;
  records.status.resize(static_cast<std::size_t>(n));
  records.has_locals.assign(static_cast<std::size_t>(n), 0);
  records.locals.setZero(n, static_cast<Eigen::Index>(locals.size()));
  int row = 0;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (row >= n) throw hapsyn::Error("view", file + ": more rows than the scene's " + std::to_string(n) + " samples");
    const std::vector<std::string> cells = split_csv_line(line);
    if (cells.size() != header.size()) {
      throw hapsyn::Error("view", file + ": row " + std::to_string(row + 1) + " has " + std::to_string(cells.size()) +
                                      " cells, the header " + std::to_string(header.size()));
    }
    records.status[static_cast<std::size_t>(row)] = cells[status];
    bool all = !locals.empty();
    for (std::size_t k = 0; k < locals.size(); ++k) {
      const std::string& cell = cells[local_at[k]];
      all = all && !cell.empty();
      records.locals(row, static_cast<Eigen::Index>(k)) = cell.empty() ? 0.0 : std::strtod(cell.c_str(), nullptr);
    }
    records.has_locals[static_cast<std::size_t>(row)] = all ? 1 : 0;
    ++row;
  }
  if (row != n) {
    throw hapsyn::Error("view", file + ": " + std::to_string(row) + " rows, the scene has " + std::to_string(n) +
                                    " samples (was the study run with other scene options?)");
  }
  return records;
}

}  // namespace hapsyn_cli
