#include "report_command.hpp"

#include "web_assets.hpp"

#include <hapsyn/error.hpp>

#include <boost/filesystem.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <iostream>
#include <unistd.h>

namespace hapsyn_cli {
namespace {

namespace fs = boost::filesystem;

// The index page's elements that report_html replaces (web/index.html must keep them as they are).
constexpr std::string_view kImportMapStart = R"(<script type="importmap">)";
constexpr std::string_view kAppScript = R"(<script type="module" src="/app.js"></script>)";
constexpr std::string_view kPrototypeScript = R"(<script type="module" src="/prototype.js"></script>)";

std::string base64(std::string_view bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out += kDigits[(v >> s) & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kDigits[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// JSON text safe inside a <script> element: every "<" (only ever inside a JSON string) written
// as "\u003c", the same string, so that no "</script" or "<!--" can end or bend the element.
std::string script_json(const hapsyn::Json& document) {
  const std::string text = document.dump();
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out += c;
    }
  }
  return out;
}

void replace_once(std::string& page, std::string_view what, const std::string& with) {
  const std::size_t at = page.find(what);
  if (at == std::string::npos) {
    throw hapsyn::Error("report", "the embedded index.html lacks the line " + std::string(what) + " (web/index.html changed?)");
  }
  page.replace(at, what.size(), with);
}

// The page's import map with every module as a data: URL: its bare names ("three",
// "three/addons/...") mapped to the data: URL of the route they name, for the modules that import
// them (a data: module cannot resolve a path), every other module by its route, for the inline
// app.js (whose base is the page).
void replace_import_map(std::string& page, const std::map<std::string, std::string>& modules) {
  const std::size_t start = page.find(kImportMapStart);
  const std::size_t end = start == std::string::npos ? start : page.find("</script>", start);
  if (end == std::string::npos) {
    throw hapsyn::Error("report", "the embedded index.html lacks its import map (web/index.html changed?)");
  }
  const std::size_t body = start + kImportMapStart.size();
  const hapsyn::Json declared = hapsyn::Json::parse(page.substr(body, end - body), nullptr, false);
  if (declared.is_discarded() || !declared.contains("imports") || !declared["imports"].is_object()) {
    throw hapsyn::Error("report", "the embedded index.html's import map is not {\"imports\": {...}} (web/index.html changed?)");
  }
  hapsyn::Json imports = hapsyn::Json::object();
  std::set<std::string> named;  // routes reached by a bare name (each module once in the page)
  for (const auto& [name, route] : declared["imports"].items()) {
    const auto module = route.is_string() ? modules.find(route.get<std::string>()) : modules.end();
    if (module == modules.end()) {
      throw hapsyn::Error("report", "the import map's \"" + name + "\" names " + route.dump() + ", not a built-in module");
    }
    imports[name] = module->second;
    named.insert(module->first);
  }
  for (const auto& [route, url] : modules) {
    if (named.count(route) == 0) imports[route] = url;
  }
  page.replace(start, end + std::string_view("</script>").size() - start,
               std::string(kImportMapStart) + hapsyn::Json{{"imports", imports}}.dump() + "</script>");
}

}  // namespace

std::string report_html(const ViewData& data) {
  if (const std::string_view missing = web_assets_missing(); !missing.empty()) {
    throw hapsyn::Error("report", "the page's assets are not built into this hapsyn: " + std::string(missing));
  }
  std::string page, app;
  std::map<std::string, std::string> modules;  // route -> data: URL
  for (const WebAsset& asset : web_assets()) {
    if (asset.route == "/") {
      page = asset.body;
    } else if (asset.route == "/app.js") {
      app = asset.body;
    } else if (asset.route != "/prototype.js") {  // the virtual prototype is left out (below)
      modules[std::string(asset.route)] = "data:text/javascript;base64," + base64(asset.body);
    }
  }
  if (app.find("</script") != std::string::npos || app.find("<!--") != std::string::npos) {
    throw hapsyn::Error("report", "app.js holds \"</script\" or \"<!--\": it cannot be inlined into the report");
  }
  replace_import_map(page, modules);
  std::string scripts;
  using Document = std::pair<const char*, const hapsyn::Json*>;
  for (const auto& [route, document] : {Document{"/api/study", &data.study}, Document{"/api/samples", &data.samples},
                                        Document{"/api/result", &data.result}}) {
    scripts += std::string("<script type=\"application/json\" data-route=\"") + route + "\">" + script_json(*document) + "</script>\n";
  }
  // The mesh files travel in the page too (meshes.js reads them before it would fetch).
  for (const MeshFile& mesh : data.meshes.files) {
    scripts += "<script type=\"application/octet-stream\" data-route=\"" + mesh.route + "\">" + base64(mesh.bytes) +
               "</script>\n";
  }
  scripts += "<script type=\"module\">\n" + app + "</script>";
  replace_once(page, kAppScript, scripts);
  // The virtual prototype needs the server (its replay document and live socket): a report has none.
  replace_once(page, kPrototypeScript, "");
  return page;
}

int report_command(const std::string& result_dir, const std::string& output, const hapsyn::Registry& registry) {
  const fs::path dir(result_dir);
  if (!fs::is_directory(dir)) {
    throw hapsyn::Error("report", result_dir + ": not a directory: give a result directory (one holding result.json)");
  }
  if (!fs::is_regular_file(dir / "result.json") && !fs::is_regular_file(dir / "sweep.json") &&
      !fs::is_regular_file(dir / "compare.json")) {
    throw hapsyn::Error("report", result_dir + ": no result.json (nor sweep.json, compare.json) in it: give the output "
                                               "directory of hapsyn run, sweep or compare");
  }
  const std::string html = report_html(load_view_data(result_dir, registry, &std::cerr));
  const fs::path file = output.empty() ? dir / "report.html" : fs::path(output);
  // Beside the target, so that the rename stays on one file system.
  const fs::path temporary = file.string() + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(temporary.string(), std::ios::binary | std::ios::trunc);
    if (out) out.write(html.data(), static_cast<std::streamsize>(html.size()));
    if (!out || !out.flush()) {
      const std::string why = std::strerror(errno);
      out.close();
      boost::system::error_code ignored;
      fs::remove(temporary, ignored);
      throw hapsyn::Error("report", "cannot write " + temporary.string() + ": " + why);
    }
  }
  if (std::rename(temporary.c_str(), file.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    boost::system::error_code ignored;
    fs::remove(temporary, ignored);
    throw hapsyn::Error("report", "cannot rename " + temporary.string() + " to " + file.string() + ": " + why);
  }
  std::cout << "hapsyn report: " << file.string() << " (" << html.size() / 1024 << " KiB)" << std::endl;
  return 0;
}

}  // namespace hapsyn_cli
