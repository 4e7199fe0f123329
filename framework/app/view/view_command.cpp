#include "view_command.hpp"

#include "http_server.hpp"
#include "live_session.hpp"
#include "replay_data.hpp"
#include "view_data.hpp"
#include "view_source.hpp"
#include "web_assets.hpp"

#include <hapsyn/error.hpp>

#include <iostream>
#include <map>

namespace hapsyn_cli {

int view_command(const std::string& path, const std::string& host, int port, const hapsyn::Registry& registry) {
  if (const std::string_view missing = web_assets_missing(); !missing.empty()) {
    throw hapsyn::Error("view", "the page's assets are not built into this hapsyn: " + std::string(missing));
  }
  const ViewData data = load_view_data(path, registry, &std::cerr);
  // The API's documents are made once; the server hands out views of them.
  const std::string study = data.study.dump();
  const std::string samples = data.samples.dump();
  const auto live = std::make_shared<const LiveModel>(data.source);
  hapsyn::Json replay_doc = replay_json(*data.source->study.problem, data.source->design);
  if (replay_doc["available"] == true) replay_doc["shoulder_frame"] = live->shoulder_frame();
  const std::string replay = replay_doc.dump();
  const std::string result = data.result.dump();
  std::map<std::string, Resource> routes;
  for (const WebAsset& asset : web_assets()) {
    routes[std::string(asset.route)] = {std::string(asset.content_type) + "; charset=utf-8", asset.body};
  }
  routes["/api/study"] = {"application/json", study};
  routes["/api/samples"] = {"application/json", samples};
  routes["/api/replay"] = {"application/json", replay};
  routes["/api/result"] = {"application/json", result};
  for (const MeshFile& mesh : data.meshes.files) routes[mesh.route] = {mesh.content_type, mesh.bytes};
  ServerSettings settings;
  settings.host = host;
  settings.port = static_cast<unsigned short>(port);
  // Told to listen beyond loopback, the server answers the names others reach it by.
  settings.loopback_hosts_only = host == "127.0.0.1" || host == "::1";
  // The live prototype: poses in on /live (each answered with its frame), frames out on /live/watch.
  SocketEndpoints sockets;
  sockets.target = "/live";
  sockets.watch_target = "/live/watch";
  sockets.connect = [live]() -> MessageHandler {
    auto session = std::make_shared<LiveSession>(*live);
    return [live, session](std::string_view message) {
      SocketReply reply;
      reply.text = session->answer(message, &reply.broadcast);
      return reply;
    };
  };
  ViewServer server(std::move(routes), settings, std::move(sockets));
  const bool v6 = host.find(':') != std::string::npos;
  std::cout << "hapsyn view: serving " << data.name << " at http://" << (v6 ? "[" + host + "]" : host) << ":"
            << server.port() << "/ (Ctrl-C stops)" << std::endl;
  server.run_until_signal();
  std::cout << "hapsyn view: stopped" << std::endl;
  return 0;
}

}  // namespace hapsyn_cli
