// `rowloc serve [--config FILE] [--listen ADDR] [--port N] [--unix-socket PATH] [--token-file FILE]
//  [--vehicles DIR] [--maps DIR] [--filters DIR] [--journal-dir DIR] [--fsync POLICY] [--threads N]
//  [--http-port N]`: the localization service (docs/service.md), with --http-port its live view in a
// browser (docs/live-view.md). Settings come from the JSON file, then the options.
// The first line on stdout says where it listens ({"type":"listening","tcp":"HOST:PORT","unix":...,
// "http":URL or null}),
// so that a script can start it with --port 0 and read the port; logs go to stderr. Sessions left
// open in the journal directory are resumed before the first connection is accepted. SIGINT and
// SIGTERM stop it gracefully (clients told, journals synced); exit 0 then, 2 for bad settings.
#include "commands.hpp"
#include "option_checks.hpp"

#include "rowloc/service/dispatcher.hpp"
#include "rowloc/service/server.hpp"

#include <nlohmann/json.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <iostream>
#include <memory>
#include <optional>

namespace rowloc::apps {
namespace {

struct ServeOptions {
  std::string config_path;
  std::optional<std::string> listen, unix_socket, token_file, vehicles, maps, filters, journal_dir, fsync;
  std::optional<int> port, threads, http_port;
};

service::ServiceSettings SettingsOf(const ServeOptions& o) {
  service::ServiceSettings s;
  if (!o.config_path.empty()) s = service::LoadServiceSettings(o.config_path);
  if (o.listen) s.listen = *o.listen;
  if (o.port) s.port = *o.port;
  if (o.http_port) s.http_port = *o.http_port;
  if (o.unix_socket) s.unix_socket = *o.unix_socket;
  if (o.token_file) s.token_file = *o.token_file;
  if (o.vehicles) s.vehicles_dir = *o.vehicles;
  if (o.maps) s.maps_dir = *o.maps;
  if (o.filters) s.filters_dir = *o.filters;
  if (o.journal_dir) s.journal_dir = *o.journal_dir;
  if (o.threads) s.threads = *o.threads;
  if (o.fsync) {
    const auto policy = service::FsyncPolicyFromName(*o.fsync);
    if (!policy) throw service::ServiceSettingsError("--fsync: must be none, interval or always");
    s.fsync = *policy;
  }
  return s;
}

/// Logs of a service go to stderr: stdout carries only the listening line.
void LogToStderr() {
  auto logger = spdlog::stderr_color_mt("rowloc-serve");
  logger->set_level(spdlog::get_level());
  spdlog::set_default_logger(logger);
}

void RunServe(const ServeOptions& options) {
  LogToStderr();
  service::Dispatcher dispatcher(SettingsOf(options));
  std::vector<std::string> problems;
  const std::size_t resumed = dispatcher.ResumeJournals(problems);
  for (const std::string& problem : problems) spdlog::warn("journal {}", problem);
  if (resumed > 0) spdlog::info("{} sessions resumed from {}", resumed, dispatcher.settings().journal_dir.string());
  service::Server server(dispatcher);
  server.Listen();
  server.CatchSignals();  // before the listening line: a SIGTERM right after it stops gracefully
  const nlohmann::ordered_json listening{
      {"type", "listening"},
      {"tcp", server.tcp_endpoint()},
      {"unix", server.unix_socket().empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(server.unix_socket())},
      {"resumed_sessions", resumed},
      {"http", server.live_view_url().empty() ? nlohmann::ordered_json(nullptr)
                                              : nlohmann::ordered_json(server.live_view_url())}};
  std::cout << listening.dump() << std::endl;
  spdlog::info("rowloc serve: listening on {}{}", server.tcp_endpoint(),
               server.unix_socket().empty() ? "" : " and " + server.unix_socket());
  if (!server.live_view_url().empty()) spdlog::info("rowloc serve: live view at {}", server.live_view_url());
  server.Run();
  spdlog::info("rowloc serve: stopped");
}

}  // namespace

void RegisterServeCommand(CLI::App& app) {
  auto o = std::make_shared<ServeOptions>();
  CLI::App* cmd = app.add_subcommand("serve", "Run the localization service (socket API, docs/service.md)");
  cmd->add_option("--config", o->config_path, "Settings file (JSON, docs/service.md §10)");
  cmd->add_option("--listen", o->listen, "TCP address (default 127.0.0.1; others need --token-file)");
  // The ranges of ValidateServiceSettings (docs/service.md §10), checked here to name the option.
  cmd->add_option("--port", o->port, "TCP port (default 7878; 0: any free port, printed on stdout)")
      ->check(IntegerInRange(0, 65535, "PORT"));
  cmd->add_option("--unix-socket", o->unix_socket, "Also listen on this Unix socket");
  cmd->add_option("--token-file", o->token_file, "Every connection must send this file's token in hello");
  cmd->add_option("--vehicles", o->vehicles, "Directory of vehicle files NAME.json (default config/vehicles)");
  cmd->add_option("--maps", o->maps, "Directory of row maps NAME.geojson (default maps)");
  cmd->add_option("--filters", o->filters, "Directory of filter files NAME.json (default config/filters)");
  cmd->add_option("--journal-dir", o->journal_dir, "Session journals (resumed at start); default: none");
  cmd->add_option("--fsync", o->fsync, "Journal fsync: none, interval (default) or always");
  cmd->add_option("--threads", o->threads, "I/O and filter threads (default 2)")->check(IntegerInRange(1, 64, "N"));
  cmd->add_option("--http-port", o->http_port,
                  "Serve the live view (browser) on this port, same address (0: any free port, printed on stdout; "
                  "-1 or default: off)")
      ->check(IntegerInRange(-1, 65535, "PORT"));
  cmd->callback([o] { RunReportingInputErrors("serve", [&o] { RunServe(*o); }); });
}

}  // namespace rowloc::apps
