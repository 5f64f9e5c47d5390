// `rowloc send LOG --to HOST:PORT --vehicle NAME|FILE [--map NAME] [--filter NAME|FILE] [--rate R]
//  -o ESTIMATES`: streams a sensor log through a running service (`rowloc serve`) as a robot
// would, in a new session, and writes the estimate stream the service sends back. For the same log,
// vehicle, filter and map this file equals `rowloc replay`'s output byte for byte (the service runs
// the same session type). --rate: `max` (as fast as the service takes them), `realtime`, or a
// multiple of real time such as `x10`. Exit 2 for bad input or a refused session, 1 when the
// service went away. The log is read as `rowloc replay` reads it (formats::BoundedLineReader): a
// line longer than 1 MiB is refused after its first 1 MiB + 2 bytes, logged with its line number
// and not sent, and so is an unterminated last line; a header that cannot be read ends the command
// (exit 2). A vehicle or filter file is read by mapio::ReadInputFile (a regular file of at most
// 16 MiB) and may nest at most 64 levels of arrays and objects, as the service allows. A filter
// file goes inline as the complete values it loads to; without --filter a vehicle file's
// recommended filter does (AddFilter), so that send and replay choose the same filter.
#include "commands.hpp"
#include "option_checks.hpp"

#include "rowloc/formats/bounded_line_reader.hpp"
#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/localization/filter_choice.hpp"
#include "rowloc/mapio/input_file.hpp"
#include "rowloc/mapio/output_file.hpp"
#include "rowloc/service/client.hpp"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <thread>

namespace rowloc::apps {
namespace {

/// The service closed the connection or stopped after the session was opened (exit 1).
class ServiceGone : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
inline constexpr int kServiceGoneExitCode = 1;

struct SendOptions {
  std::string log_path, to = "127.0.0.1:7878", vehicle, map, filter, output_path, rate = "max", session;
  double period_s = 0.1;
};

/// Time scale of --rate: 0 for max, else seconds of wall time per second of log time.
double WallPerLogSecond(const std::string& rate) {
  if (rate == "max") return 0.0;
  if (rate == "realtime") return 1.0;
  if (rate.size() > 1 && rate.front() == 'x') {
    std::size_t used = 0;
    double factor = 0.0;
    try {
      factor = std::stod(rate.substr(1), &used);
    } catch (const std::exception&) {
    }
    if (used == rate.size() - 1 && factor > 0 && std::isfinite(factor)) return 1.0 / factor;
  }
  throw std::invalid_argument("--rate: expected max, realtime or xN (N > 0), got '" + rate + "'");
}

/// Deepest nesting of arrays and objects in the header and an inline configuration: the service
/// refuses deeper request lines (docs/service.md §9), and copying or dumping a value recurses once
/// per level (a vehicle file nested 10^6 levels deep crashed `send`).
constexpr int kMaxNesting = 64;

/// `text` as JSON (discarded when invalid); throws std::invalid_argument naming `source` when it
/// nests deeper than kMaxNesting, without building the deeper values.
nlohmann::json ParseShallowJson(const std::string& text, const std::string& source) {
  bool too_deep = false;
  nlohmann::json value = nlohmann::json::parse(
      text,
      [&too_deep](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
        if (depth > kMaxNesting) too_deep = true;
        return !too_deep;  // discards the values while the parser finishes
      },
      false);
  if (too_deep) {
    throw std::invalid_argument(source + ": nested deeper than " + std::to_string(kMaxNesting) +
                                " levels of arrays and objects (the service's limit)");
  }
  return value;
}

/// True when `value` names an existing file (of any kind but a directory): it is read and sent
/// inline; anything else is a name on the server.
bool NamesAFile(const std::string& value) {
  std::error_code ec;
  const std::filesystem::file_type type = std::filesystem::status(value, ec).type();
  return type != std::filesystem::file_type::not_found && type != std::filesystem::file_type::none &&
         type != std::filesystem::file_type::directory;
}

/// A vehicle or filter: a file (sent inline) when the path names one, else a name on the server.
void AddConfig(nlohmann::json& request, const std::string& value, const char* name_key, const char* inline_key,
               const char* what) {
  if (value.empty()) return;
  if (!NamesAFile(value)) {
    request[name_key] = value;
    return;
  }
  // Regular files of at most 16 MiB only: a FIFO, a device or a huge file is refused unread.
  const std::string text = mapio::ReadInputFile(value, mapio::kMaxConfigFileBytes, what);
  nlohmann::json config = ParseShallowJson(text, value);
  if (config.is_discarded()) throw std::invalid_argument(value + ": not valid JSON");
  if (!config.is_object()) throw std::invalid_argument(value + ": valid JSON, but not an object");
  request[inline_key] = std::move(config);
}

/// The filter of the session: a filter file is sent inline as its complete values (what it loads
/// to with the files it extends, which the service could not resolve), a name is left to the
/// server; without --filter, a vehicle file's recommended filter is sent inline (so that the
/// session runs as `rowloc replay --vehicle FILE` does), and a vehicle name's is the server's.
void AddFilter(nlohmann::json& request, const std::string& filter, const std::string& vehicle) {
  std::optional<localization::FilterChoice> choice;
  if (!filter.empty() && !NamesAFile(filter)) {
    request["filter"] = filter;
  } else if (!filter.empty()) {
    choice = localization::FilterChoice{localization::LoadFilterConfig(filter), filter,
                                        localization::FilterSource::kGiven};
  } else if (NamesAFile(vehicle)) {
    choice = localization::LoadRecommendedFilter(mapio::LoadVehicleFile(vehicle), vehicle);
  }
  if (!choice) return;
  request["filter_config"] = nlohmann::json::parse(localization::FilterConfigJson(choice->config));
  spdlog::info("{}, sent inline", localization::DescribeFilterChoice(*choice, vehicle));
}

/// The log's header line: the first non-empty line, refused (exit 2) as `rowloc replay` refuses it.
std::string ReadHeaderLine(formats::BoundedLineReader& lines, const std::string& log_path) {
  std::string line;
  for (;;) {
    const formats::BoundedLineReader::Result result = lines.Read(line);
    const std::string where = log_path + ":" + std::to_string(lines.line_number());
    switch (result) {
      case formats::BoundedLineReader::Result::kEnd:
        throw std::runtime_error(log_path + ": empty sensor log");
      case formats::BoundedLineReader::Result::kReadError:
        throw std::runtime_error(log_path + ":" + std::to_string(lines.line_number() + 1) + ": line: read error");
      case formats::BoundedLineReader::Result::kTooLong:
        throw std::runtime_error(where + ": line: longer than 1 MiB (" + std::to_string(formats::kMaxLogLineBytes) +
                                 " bytes, the protocol's limit)");
      case formats::BoundedLineReader::Result::kUnterminated:
        throw std::runtime_error(where + ": line: not terminated by a newline (a truncated log?)");
      case formats::BoundedLineReader::Result::kLine:
        if (!line.empty()) return line;
        break;
    }
  }
}

void DrainPushed(service::Client& client, const std::string& session, std::ostream& out, std::size_t& lines) {
  while (const std::optional<std::string> line = client.ReadPushed(std::chrono::milliseconds(0))) {
    if (line->starts_with(R"({"type":"shutdown")")) {  // not an estimate line: the server is stopping
      const nlohmann::json notice = nlohmann::json::parse(*line, nullptr, false);
      throw ServiceGone("the service is stopping: " +
                        (notice.is_object() ? notice.value("message", std::string()) : std::string()));
    }
    out << service::WithoutSessionKey(*line, session) << '\n';
    ++lines;
  }
  while (const std::optional<nlohmann::json> error = client.TakeError()) {
    spdlog::warn("service: line {}: {}: {}", error->value("line", 0), error->value("code", ""),
                 error->value("message", ""));
  }
}

void RunSend(const SendOptions& o) {
  const auto file_or_name = [](const std::string& value) { return NamesAFile(value) ? value : std::string(); };
  CheckCommandFiles({{"log", o.log_path}, {"--vehicle", file_or_name(o.vehicle)}, {"--filter", file_or_name(o.filter)}},
                    {{"--output", o.output_path}});
  const double wall_per_log_s = WallPerLogSecond(o.rate);
  std::ifstream log(o.log_path, std::ios::binary);
  if (!log) throw std::runtime_error(o.log_path + ": cannot open sensor log: " + std::strerror(errno));
  formats::BoundedLineReader lines(log, formats::kMaxLogLineBytes);
  const std::string header_line = ReadHeaderLine(lines, o.log_path);
  const std::string header_where = o.log_path + ":" + std::to_string(lines.line_number());
  const nlohmann::json header = ParseShallowJson(header_line, header_where);
  if (!header.is_object() || header.value("type", "") != "log_header") {
    throw std::runtime_error(header_where + ": the first line must be a log_header");
  }
  nlohmann::json open{{"header", header}, {"period_s", o.period_s}};
  AddConfig(open, o.vehicle, "vehicle", "vehicle_config", "vehicle file");
  AddFilter(open, o.filter, o.vehicle);
  if (!o.map.empty()) open["map"] = o.map;
  if (!o.session.empty()) open["session"] = o.session;
  // Before the session is opened: a bad output path must not leave a session open on the server.
  mapio::OutputFile output(o.output_path);  // renamed over the target when the whole stream is in
  std::ostream& out = output.stream();
  service::Client client = service::Client::Connect(o.to);
  client.Hello();
  const std::string session = client.OpenSession(open);
  client.Subscribe(session, "estimates");
  spdlog::info("send {} to {} (session {}, rate {})", o.log_path, o.to, session, o.rate);

  const auto start = std::chrono::steady_clock::now();
  std::optional<double> first_t;
  std::size_t sent = 0, written = 0, refused = 0;
  std::string line;
  nlohmann::json closed;
  try {
    for (;;) {
      const formats::BoundedLineReader::Result result = lines.Read(line);
      const std::size_t line_number = lines.line_number();
      if (result == formats::BoundedLineReader::Result::kEnd) break;
      if (result == formats::BoundedLineReader::Result::kReadError) {  // the log's fault (exit 2), session closed first
        client.CloseSession(session);
        throw std::invalid_argument(o.log_path + ":" + std::to_string(line_number + 1) + ": line: read error");
      }
      // As `rowloc replay`: a line the reader refuses is logged with its number, not sent, and the log goes on.
      if (result == formats::BoundedLineReader::Result::kTooLong) {
        spdlog::warn("{}:{}: rejected: line: longer than 1 MiB ({} bytes, the protocol's limit)", o.log_path,
                     line_number, formats::kMaxLogLineBytes);
        ++refused;
        continue;
      }
      if (result == formats::BoundedLineReader::Result::kUnterminated) {
        spdlog::warn("{}:{}: rejected: line: not terminated by a newline (a truncated log?)", o.log_path, line_number);
        ++refused;
        continue;
      }
      if (line.empty()) continue;
      if (wall_per_log_s > 0) {
        const nlohmann::json message = nlohmann::json::parse(line, nullptr, false);
        if (message.is_object() && message.contains("t") && message["t"].is_number()) {
          const double t = message["t"].get<double>();
          if (!first_t) first_t = t;
          std::this_thread::sleep_until(start + std::chrono::duration<double>((t - *first_t) * wall_per_log_s));
        }
      }
      std::string message;
      try {
        message = service::WithSessionKey(line, session);
      } catch (const std::invalid_argument& e) {  // the log's fault (exit 2); the session is closed first
        client.CloseSession(session);
        throw std::invalid_argument(o.log_path + ":" + std::to_string(line_number) + ": " + e.what());
      }
      client.SendLine(message);
      if (++sent % 256 == 0) DrainPushed(client, session, out, written);
    }
    closed = client.CloseSession(session);  // applies what the reorder window holds
    DrainPushed(client, session, out, written);
  } catch (const service::ClientError&) {
    throw;  // a refusal (exit 2)
  } catch (const ServiceGone&) {
    throw;
  } catch (const std::runtime_error& e) {  // the connection: a failed write, a closed connection, no reply
    throw ServiceGone("the service went away after " + std::to_string(sent) + " messages: " + e.what());
  }
  output.Commit();
  if (refused > 0) spdlog::warn("{} lines of {} refused (not sent)", refused, o.log_path);
  spdlog::info("sent {} messages ({} accepted) in {:.2f} s; wrote {} lines to {}", sent,
               closed.value("messages", 0), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
               written, o.output_path);
}

}  // namespace

void RegisterSendCommand(CLI::App& app) {
  auto o = std::make_shared<SendOptions>();
  CLI::App* cmd = app.add_subcommand("send", "Stream a sensor log through a running service: estimate stream");
  cmd->add_option("log", o->log_path, "Sensor log (docs/protocol.md §1)")->required();
  cmd->add_option("--to", o->to, "The service: HOST:PORT or unix:PATH (default 127.0.0.1:7878)");
  cmd->add_option("--vehicle", o->vehicle, "Vehicle name on the server, or a vehicle file (sent inline)")->required();
  cmd->add_option("--map", o->map, "Row map name on the server");
  cmd->add_option("--filter", o->filter,
                  "Filter name on the server, or a filter file (sent inline as the values it loads to); default: "
                  "the vehicle's recommended filter (a vehicle file's sent inline, a vehicle name's chosen by the server)");
  cmd->add_option("--session", o->session, "Session name (default: the server's)");
  cmd->add_option("--rate", o->rate, "max (default), realtime, or xN: N times real time");
  cmd->add_option("--period", o->period_s, "Log time between estimate lines, s")->check(PositiveNumber());
  cmd->add_option("-o,--output", o->output_path, "Estimate stream to write (docs/protocol.md §3)")->required();
  cmd->callback([o] {
    std::optional<std::string> gone;
    RunReportingInputErrors("send", [&] {
      try {
        RunSend(*o);
      } catch (const ServiceGone& e) {
        gone = e.what();
      }
    });
    if (gone) {
      spdlog::error("send: {}", *gone);
      throw CLI::RuntimeError(kServiceGoneExitCode);
    }
  });
}

}  // namespace rowloc::apps
