// Request handling of the service (see dispatcher.hpp; the protocol is docs/service.md).
#include "rowloc/service/dispatcher.hpp"

#include "rowloc/formats/bounded_line_reader.hpp"
#include "rowloc/formats/ndjson_writing.hpp"
#include "rowloc/formats/sensor_log_reader.hpp"
#include "rowloc/localization/filter_config.hpp"
#include "rowloc/mapio/input_file.hpp"
#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/mapio/config_overlay.hpp"
#include "rowloc/mapio/row_map_geojson.hpp"
#include "rowloc/mapio/vehicle_config.hpp"
#include "rowloc/service/named_files.hpp"
#include "rowloc/service/session_filter.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <fstream>

namespace rowloc::service {
namespace {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

constexpr std::size_t kMaxIdBytes = 128;
constexpr std::uintmax_t kMaxConfigFileBytes = 4 << 20;
/// A session's metadata in the journal directory holds one open_session request (at most
/// kMaxLineBytesLimit) with its vehicle and filter (each at most kMaxConfigFileBytes): 128 MiB is
/// above anything the server writes there.
constexpr std::uintmax_t kMaxSessionMetadataBytes = std::uintmax_t{128} << 20;
/// Deepest nesting of arrays and objects in a request line (the deepest real request, an inline
/// configuration, has about 5 levels). nlohmann parses any depth, but copying or dumping a value
/// recurses once per level: a header nested 32k levels deep overflowed the stack (found by
/// fuzz/service_dispatch_fuzz.cpp), and a 1 MiB line can nest 500k.
constexpr std::size_t kMaxNestingDepth = 64;

const std::vector<std::string_view> kSensorTypes = {"gps", "imu", "wheels", "steering", "ultrasonic", "vio"};

bool IsSensorType(std::string_view type) {
  return std::find(kSensorTypes.begin(), kSensorTypes.end(), type) != kSensorTypes.end();
}

[[noreturn]] void Fail(ErrorCode code, const std::string& message) { throw ServiceError(code, message); }

/// The value of a required key of the request.
const Json& Required(const Json& request, const char* key) {
  const auto it = request.find(key);
  if (it == request.end()) Fail(ErrorCode::kMissingField, std::string(key) + ": missing");
  return *it;
}

std::string RequiredString(const Json& request, const char* key) {
  const Json& value = Required(request, key);
  if (!value.is_string()) Fail(ErrorCode::kInvalidField, std::string(key) + ": must be a string");
  return value.get<std::string>();
}

std::optional<std::string> OptionalString(const Json& request, const char* key) {
  const auto it = request.find(key);
  if (it == request.end() || it->is_null()) return std::nullopt;
  if (!it->is_string()) Fail(ErrorCode::kInvalidField, std::string(key) + ": must be a string");
  return it->get<std::string>();
}

/// A finite number in [lo, hi], or `fallback` when the key is absent.
double OptionalNumber(const Json& request, const char* key, double fallback, double lo, double hi) {
  const auto it = request.find(key);
  if (it == request.end() || it->is_null()) return fallback;
  if (!it->is_number()) Fail(ErrorCode::kInvalidField, std::string(key) + ": must be a number");
  const double value = it->get<double>();
  if (!std::isfinite(value) || value < lo || value > hi) {
    Fail(ErrorCode::kInvalidField,
         std::string(key) + ": " + std::to_string(value) + " is outside [" + std::to_string(lo) + ", " +
             std::to_string(hi) + "]");
  }
  return value;
}

/// A vehicle or filter file of the server's directories as a JSON object, through
/// mapio::ReadInputFile: a FIFO, a device or a file above kMaxConfigFileBytes is refused unread
/// (it could hang or exhaust the server), and so is nesting deeper than kMaxNestingDepth (copying
/// or dumping the value recurses once per level). Fails with kInvalidConfig naming `what` and `name`.
Json ReadConfigFile(const std::filesystem::path& path, const std::string& what, const std::string& name) {
  const std::string quoted = what + " '" + name + "'";
  std::string text;
  try {
    text = mapio::ReadInputFile(path, kMaxConfigFileBytes, what + " file");
  } catch (const mapio::InputFileError& e) {
    Fail(ErrorCode::kInvalidConfig, quoted + " (" + path.filename().string() + "): " + e.reason());
  }
  if (mapio::JsonNestedDeeperThan(text, kMaxNestingDepth)) {
    Fail(ErrorCode::kInvalidConfig, quoted + ": arrays and objects nested deeper than " +
                                        std::to_string(kMaxNestingDepth) + " levels");
  }
  Json object = Json::parse(text, nullptr, false);
  if (!object.is_object()) Fail(ErrorCode::kInvalidConfig, quoted + ": not a JSON object");
  return object;
}

/// A vehicle or filter configuration by name or inline, as a JSON object.
Json ConfigObject(const Json& request, const char* name_key, const char* inline_key, const std::filesystem::path& dir,
                  ErrorCode missing, const char* what, std::size_t max_inline_bytes, std::string& name,
                  std::filesystem::path& file) {
  file.clear();
  if (const auto it = request.find(inline_key); it != request.end() && !it->is_null()) {
    if (request.contains(name_key)) {
      Fail(ErrorCode::kInvalidField, std::string(inline_key) + ": give either " + name_key + " or " + inline_key);
    }
    if (!it->is_object()) Fail(ErrorCode::kInvalidField, std::string(inline_key) + ": must be an object");
    if (it->dump().size() > max_inline_bytes) {
      Fail(ErrorCode::kLimitExceeded, std::string(inline_key) + ": larger than max_inline_config_bytes (" +
                                          std::to_string(max_inline_bytes) + ")");
    }
    name.clear();
    return *it;
  }
  const std::optional<std::string> given = OptionalString(request, name_key);
  if (!given) return Json(nullptr);
  name = *given;
  file = ResolveNamedFile(dir, name, ".json", missing, what);
  return ReadConfigFile(file, what, name);
}

geometry::GeoOrigin OriginOf(const Json& value, const char* key) {
  if (!value.is_object()) Fail(ErrorCode::kInvalidField, std::string(key) + ": must be an object");
  geometry::GeoOrigin origin;
  const auto number = [&](const char* k) {
    const Json& v = Required(value, k);
    if (!v.is_number() || !std::isfinite(v.get<double>())) {
      Fail(ErrorCode::kInvalidField, std::string(key) + "." + k + ": must be a finite number");
    }
    return v.get<double>();
  };
  origin = {number("latitude_deg"), number("longitude_deg"), number("altitude_m")};
  const std::string problem =
      mapio::GeodeticPositionProblem(origin.latitude_deg, origin.longitude_deg, origin.altitude_m);
  if (!problem.empty()) Fail(ErrorCode::kInvalidField, std::string(key) + ": " + problem);
  return origin;
}

/// The session's log header: from the request's `header` (a log_header object), else the
/// vehicle's wheel and ranger order with `origin` or the map's origin.
formats::LogHeader HeaderOf(const Json& request, const mapio::VehicleConfig& vehicle, const geometry::RowMap* map) {
  if (const auto it = request.find("header"); it != request.end() && !it->is_null()) {
    if (!it->is_object()) Fail(ErrorCode::kInvalidField, "header: must be an object (a log_header)");
    Json header = *it;
    header["type"] = "log_header";
    for (const char* key : {"source", "scenario", "vehicle"}) {
      if (!header.contains(key)) header[key] = "";
    }
    if (!header.contains("protocol")) header["protocol"] = "rowloc/1";
    try {
      return formats::ParseLogHeader(header.dump(), "header");
    } catch (const formats::SensorLogError& e) {
      Fail(e.reason().rfind("missing", 0) == 0 ? ErrorCode::kMissingField : ErrorCode::kInvalidField,
           "header." + e.subject() + ": " + e.reason());
    }
  }
  formats::LogHeader header;
  header.protocol = "rowloc/1";
  header.source = "rowloc serve";
  header.vehicle = vehicle.name;
  for (const auto& wheel : vehicle.wheels) header.wheels.push_back(wheel.name);
  for (const auto& ranger : vehicle.ultrasonic) header.ultrasonic.push_back(ranger.name);
  if (const auto it = request.find("origin"); it != request.end() && !it->is_null()) {
    header.origin = OriginOf(*it, "origin");
  } else if (map) {
    header.origin = map->origin;
  } else {
    Fail(ErrorCode::kMissingField, "origin: missing (give header, origin or map: the WGS84 origin of the frame)");
  }
  return header;
}

std::optional<std::array<double, 6>> InitialPoseOf(const Json& request) {
  const auto it = request.find("initial_pose");
  if (it == request.end() || it->is_null()) return std::nullopt;
  if (!it->is_object()) Fail(ErrorCode::kInvalidField, "initial_pose: must be an object");
  std::array<double, 6> pose{};
  const char* keys[] = {"t", "x_m", "y_m", "phi_rad", "sigma_xy_m", "sigma_phi_rad"};
  for (std::size_t i = 0; i < 6; ++i) {
    const Json& v = Required(*it, keys[i]);
    if (!v.is_number() || !std::isfinite(v.get<double>())) {
      Fail(ErrorCode::kInvalidField, std::string("initial_pose.") + keys[i] + ": must be a finite number");
    }
    pose[i] = v.get<double>();
  }
  if (!(pose[4] > 0 && pose[4] < 1e4 && pose[5] > 0 && pose[5] < 10)) {
    Fail(ErrorCode::kInvalidField, "initial_pose: sigma_xy_m must be in (0, 1e4) m and sigma_phi_rad in (0, 10) rad");
  }
  return pose;
}

/// The journal's log_header line: the sensor-log header plus the session's name and reorder window.
std::string JournalHeaderLine(const SessionSpec& spec, const std::string& vehicle_name) {
  OrderedJson j;
  j["type"] = "log_header";
  j["protocol"] = "rowloc/1";
  j["source"] = "rowloc serve";
  j["scenario"] = spec.name;
  j["vehicle"] = vehicle_name;
  j["origin"] = formats::ndjson::OriginJson(spec.header.origin);
  j["wheels"] = spec.header.wheels;
  j["ultrasonic"] = spec.header.ultrasonic;
  j["session"] = spec.name;
  j["reorder_window_s"] = spec.reorder_window_s;
  return j.dump();
}

/// Constant-time comparison of a presented token with the server's.
bool SameToken(const std::string& given, const std::string& expected) {
  unsigned char difference = given.size() == expected.size() ? 0 : 1;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    difference |= static_cast<unsigned char>(expected[i] ^ (i < given.size() ? given[i] : 0));
  }
  return difference == 0;
}

}  // namespace

Dispatcher::Dispatcher(ServiceSettings settings) : settings_(std::move(settings)) {
  ValidateServiceSettings(settings_);
  if (!settings_.token_file.empty()) token_ = ReadToken(settings_.token_file);
}

std::size_t Dispatcher::session_count() const {
  std::lock_guard lock(registry_mutex_);
  return sessions_.size();
}

std::shared_ptr<ServiceSession> Dispatcher::FindSession(const std::string& name) const {
  std::lock_guard lock(registry_mutex_);
  const auto it = sessions_.find(name);
  return it == sessions_.end() ? nullptr : it->second;  // null while being opened
}

bool Dispatcher::TokenMatches(std::string_view given) const { return token_.empty() || SameToken(std::string(given), token_); }

std::shared_ptr<ServiceSession> Dispatcher::Session(const Json& request) const {
  const std::string name = RequiredString(request, "session");
  std::shared_ptr<ServiceSession> session = FindSession(name);
  if (!session) Fail(ErrorCode::kUnknownSession, "session '" + name + "' is not open");
  return session;
}

void Dispatcher::Reply(ClientContext& client, OrderedJson reply, const Json& id) {
  OrderedJson line;
  line["type"] = std::move(reply["type"]);
  line["id"] = id;
  reply.erase("type");
  line.update(reply);
  client.sink->Push(line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), false);
}

void Dispatcher::ReplyError(ClientContext& client, ErrorCode code, const std::string& message, const Json& id,
                            std::size_t line_number) {
  stats_.CountReject(code);
  OrderedJson line{{"type", "error"}, {"id", id}, {"code", ErrorCodeName(code)}, {"message", message},
                   {"line", line_number}};
  client.sink->Push(line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), false);
}

void Dispatcher::HandleOversizedLine(ClientContext& client, std::size_t line_number) {
  ++stats_.lines;
  ReplyError(client, ErrorCode::kLineTooLong,
             "line " + std::to_string(line_number) + " is longer than max_line_bytes (" +
                 std::to_string(settings_.max_line_bytes) + "); it was skipped",
             nullptr, line_number);
}

void Dispatcher::HandleLine(ClientContext& client, std::string_view line, std::size_t line_number) {
  const auto start = std::chrono::steady_clock::now();
  ++stats_.lines;
  Json id = nullptr;
  try {
    if (mapio::JsonNestedDeeperThan(line, kMaxNestingDepth)) {
      Fail(ErrorCode::kLimitExceeded, "arrays and objects nested deeper than " + std::to_string(kMaxNestingDepth) +
                                          " levels");
    }
    Json request;
    try {
      request = Json::parse(line);
    } catch (const Json::out_of_range& e) {
      Fail(ErrorCode::kInvalidField, std::string("a number beyond the range of a double (") + e.what() + ")");
    } catch (const Json::exception& e) {
      Fail(ErrorCode::kMalformedJson, std::string("not JSON: ") + e.what());
    }
    if (!request.is_object()) Fail(ErrorCode::kNotAnObject, std::string("a request is a JSON object, got ") +
                                                                 request.type_name());
    if (const auto it = request.find("id"); it != request.end()) {
      const bool valid = it->is_number_integer() || (it->is_string() && it->get<std::string>().size() <= kMaxIdBytes);
      if (!valid) Fail(ErrorCode::kInvalidField, "id: must be an integer or a string of at most 128 characters");
      id = *it;
    }
    const std::string type = RequiredString(request, "type");
    if (shutting_down_) Fail(ErrorCode::kShuttingDown, "the server is shutting down");
    if (!token_.empty() && !client.authenticated && type != "hello") {
      Fail(ErrorCode::kUnauthorized, "this server needs a token: send hello with \"token\" first");
    }
    Dispatch(client, request, id, type, line);
  } catch (const ServiceError& e) {
    ReplyError(client, e.code(), e.what(), id, line_number);
  } catch (const std::exception& e) {
    spdlog::error("internal error on line {}: {}", line_number, e.what());
    ReplyError(client, ErrorCode::kInternal, e.what(), id, line_number);
  }
  stats_.latency.Record(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
}

void Dispatcher::Dispatch(ClientContext& client, const Json& request, const Json& id, std::string_view type,
                          std::string_view line) {
  if (IsSensorType(type)) {
    HandleSensorMessage(client, request, id, line);
  } else if (type == "hello") {
    Reply(client, Hello(client, request), id);
  } else if (type == "open_session") {
    Reply(client, OpenSession(request), id);
  } else if (type == "close_session") {
    Reply(client, CloseSession(request), id);
  } else if (type == "get_state") {
    OrderedJson state{{"type", "state"}};
    state.update(Session(request)->State());
    Reply(client, std::move(state), id);
  } else if (type == "subscribe") {
    Subscribe(client, request, id);
  } else if (type == "unsubscribe") {
    const std::shared_ptr<ServiceSession> session = Session(request);
    const bool was = session->Unsubscribe(client.sink->client_id());
    Reply(client, OrderedJson{{"type", "unsubscribed"}, {"session", session->name()}, {"was_subscribed", was}}, id);
  } else if (type == "list_maps") {
    Reply(client, ListMaps(), id);
  } else if (type == "list_vehicles") {
    Reply(client, ListVehicles(), id);
  } else if (type == "list_sessions") {
    Reply(client, ListSessions(), id);
  } else if (type == "stats") {
    Reply(client, Stats(), id);
  } else {
    Fail(ErrorCode::kUnknownType, "type '" + std::string(type) +
                                      "' is not a request (hello, open_session, close_session, get_state, subscribe, "
                                      "unsubscribe, list_maps, list_vehicles, list_sessions, stats) or a sensor "
                                      "message (gps, imu, wheels, steering, ultrasonic, vio)");
  }
}

void Dispatcher::HandleSensorMessage(ClientContext& client, const Json& request, const Json& id,
                                     std::string_view line) {
  const std::shared_ptr<ServiceSession> session = Session(request);
  formats::SensorMessage message;
  try {
    message = formats::ParseSensorMessageObject(request, session->header(), session->name(), 0);
  } catch (const formats::SensorLogError& e) {
    const bool missing = e.reason().rfind("missing", 0) == 0;
    Fail(missing ? ErrorCode::kMissingField : ErrorCode::kInvalidField, e.subject() + ": " + e.reason());
  }
  ++stats_.sensor_messages;
  const double time_s = formats::TimeOf(message);
  const std::vector<std::string> refusals = session->Submit(line, std::move(message));
  if (std::find(client.touched.begin(), client.touched.end(), session) == client.touched.end()) {
    client.touched.push_back(session);
  }
  if (!refusals.empty()) {
    std::string text = "the filter refused " + refusals.front();
    if (refusals.size() > 1) text += " (and " + std::to_string(refusals.size() - 1) + " more)";
    Fail(ErrorCode::kRejected, text);
  }
  if (!id.is_null()) {
    Reply(client, OrderedJson{{"type", "ack"}, {"session", session->name()}, {"t", time_s}, {"pending", session->pending()}}, id);
  }
}

void Dispatcher::EndBatch(ClientContext& client) {
  for (const std::shared_ptr<ServiceSession>& session : client.touched) {
    try {
      session->FlushJournal(false);
    } catch (const std::exception& e) {
      spdlog::error("session {}: {}", session->name(), e.what());
    }
  }
  client.touched.clear();
}

void Dispatcher::ClientGone(ClientContext& client) {
  EndBatch(client);
  std::vector<std::shared_ptr<ServiceSession>> sessions;
  {
    std::lock_guard lock(registry_mutex_);
    for (const auto& [name, session] : sessions_) {
      if (session) sessions.push_back(session);
    }
  }
  for (const auto& session : sessions) session->Unsubscribe(client.sink->client_id());
}

Dispatcher::OrderedJson Dispatcher::Hello(ClientContext& client, const Json& request) {
  if (const std::optional<std::string> protocol = OptionalString(request, "protocol")) {
    if (protocol->rfind("rowloc-service/1", 0) != 0 ||
        (protocol->size() > 16 && (*protocol)[16] != '.')) {
      Fail(ErrorCode::kUnsupportedProtocol, "protocol '" + *protocol + "' is not supported (this server speaks " +
                                                std::string(kServiceProtocol) + ")");
    }
  }
  if (!token_.empty()) {
    const std::optional<std::string> token = OptionalString(request, "token");
    if (!token || !SameToken(*token, token_)) Fail(ErrorCode::kUnauthorized, "hello: wrong or missing token");
    client.authenticated = true;
  }
  return OrderedJson{{"type", "hello"},
                     {"protocol", kServiceProtocol},
                     {"server", "rowloc " ROWLOC_VERSION},
                     {"sensor_protocol", "rowloc/1"},
                     {"auth", token_.empty() ? "none" : "token"},
                     {"limits",
                      {{"max_line_bytes", settings_.max_line_bytes},
                       {"max_sessions", settings_.max_sessions},
                       {"max_queue_lines", settings_.max_queue_lines},
                       {"max_inline_config_bytes", settings_.max_inline_config_bytes},
                       {"reorder_window_s", settings_.reorder_window_s},
                       {"max_reorder_window_s", settings_.max_reorder_window_s}}}};
}

std::string Dispatcher::NewSessionName() {
  for (;;) {
    std::string name = std::to_string(++generated_names_);
    name.insert(name.begin(), 's');  // not "s" + ...: GCC 12 warns falsely (-Wrestrict) on that
    if (!sessions_.contains(name)) return name;
  }
}

std::shared_ptr<const geometry::RowMap> Dispatcher::LoadMap(const std::string& name) {
  const std::filesystem::path path = ResolveNamedFile(settings_.maps_dir, name, ".geojson", ErrorCode::kUnknownMap, "map");
  std::lock_guard lock(maps_mutex_);
  if (const auto it = maps_.find(path.string()); it != maps_.end()) return it->second;
  try {
    auto map = std::make_shared<const geometry::RowMap>(mapio::ReadRowMapGeoJson(path));
    maps_[path.string()] = map;
    return map;
  } catch (const std::exception& e) {
    Fail(ErrorCode::kInvalidConfig, "map '" + name + "': " + e.what());
  }
}

std::shared_ptr<ServiceSession> Dispatcher::BuildSession(SessionSpec spec, std::unique_ptr<SessionJournal> journal) {
  try {
    mapio::VehicleConfig vehicle = mapio::ParseVehicleConfig(spec.vehicle_config.dump(), "vehicle");
    localization::FilterConfig filter = spec.filter_config.is_null()
                                            ? localization::FilterConfig{}
                                            : localization::ParseFilterConfig(spec.filter_config.dump(), "filter");
    localization::SessionOptions options;
    options.estimate_period_s = spec.period_s;
    localization::LocalizationSession session(std::move(vehicle), std::move(filter), spec.header, options);
    if (!spec.map.empty()) session.AttachRowMap(*LoadMap(spec.map));
    if (spec.initial_pose) {
      const auto& p = *spec.initial_pose;
      const Eigen::Vector3d sigma(p[4], p[4], p[5]);
      session.SetPose(p[0], Eigen::Vector3d(p[1], p[2], p[3]), sigma.cwiseAbs2().asDiagonal().toDenseMatrix());
    }
    return std::make_shared<ServiceSession>(std::move(spec), std::move(session), std::move(journal),
                                            settings_.max_time_jump_s);
  } catch (const ServiceError&) {
    throw;
  } catch (const std::exception& e) {
    Fail(ErrorCode::kInvalidConfig, e.what());
  }
}

Dispatcher::OrderedJson Dispatcher::OpenSession(const Json& request) {
  SessionSpec spec;
  if (const std::optional<std::string> name = OptionalString(request, "session")) {
    if (!IsPlainName(*name)) Fail(ErrorCode::kInvalidName, "session '" + *name + "' is not a plain name");
    spec.name = *name;
  }
  if (!request.contains("vehicle") && !request.contains("vehicle_config")) {
    Fail(ErrorCode::kMissingField, "vehicle: missing (a vehicle name, or vehicle_config inline)");
  }
  std::filesystem::path vehicle_file, filter_file;
  spec.vehicle_config = ConfigObject(request, "vehicle", "vehicle_config", settings_.vehicles_dir,
                                     ErrorCode::kUnknownVehicle, "vehicle", settings_.max_inline_config_bytes,
                                     spec.vehicle, vehicle_file);
  const Json filter = ConfigObject(request, "filter", "filter_config", settings_.filters_dir,
                                   ErrorCode::kUnknownFilter, "filter", settings_.max_inline_config_bytes, spec.filter,
                                   filter_file);
  mapio::VehicleConfig vehicle;
  try {
    vehicle = mapio::ParseVehicleConfig(spec.vehicle_config.dump(), "vehicle");
  } catch (const std::exception& e) {
    Fail(ErrorCode::kInvalidConfig, e.what());
  }
  // Complete values (the file's, its bases', the defaults'), or the vehicle's recommended filter.
  const SessionFilter session_filter =
      ResolveSessionFilter(filter, filter_file, spec.filter, spec.vehicle_config, vehicle_file, spec.vehicle);
  spec.filter_config = session_filter.config;
  spec.filter = session_filter.name;
  std::shared_ptr<const geometry::RowMap> map;
  if (const std::optional<std::string> name = OptionalString(request, "map")) {
    map = LoadMap(*name);
    spec.map = *name;
  }
  spec.header = HeaderOf(request, vehicle, map.get());
  spec.period_s = OptionalNumber(request, "period_s", 0.1, 1e-3, 3600.0);
  spec.reorder_window_s = OptionalNumber(request, "reorder_window_s", settings_.reorder_window_s, 0.0,
                                         settings_.max_reorder_window_s);
  spec.initial_pose = InitialPoseOf(request);

  {
    // The name is reserved (a null entry) while the session is built outside the registry's lock.
    std::lock_guard lock(registry_mutex_);
    if (sessions_.size() >= settings_.max_sessions) {
      Fail(ErrorCode::kLimitExceeded, "the server has max_sessions (" + std::to_string(settings_.max_sessions) +
                                          ") sessions open");
    }
    if (spec.name.empty()) spec.name = NewSessionName();
    if (sessions_.contains(spec.name)) Fail(ErrorCode::kSessionExists, "session '" + spec.name + "' is already open");
    sessions_[spec.name] = nullptr;
  }
  const std::string name = spec.name;
  std::shared_ptr<ServiceSession> session;
  try {
    if (!settings_.journal_dir.empty() &&
        std::filesystem::exists(SessionJournal::MetadataPath(settings_.journal_dir, spec.name))) {
      Fail(ErrorCode::kSessionExists, "session '" + spec.name + "' has an open journal that was not resumed");
    }
    const std::string metadata = spec.ToJson().dump();
    const std::string header_line = JournalHeaderLine(spec, vehicle.name);
    session = BuildSession(std::move(spec), nullptr);  // a bad configuration leaves no journal behind
    if (!settings_.journal_dir.empty()) {
      session->AttachJournal(SessionJournal::Create(settings_.journal_dir, name, metadata, header_line,
                                                    settings_.max_journal_bytes, settings_.fsync));
    }
  } catch (...) {
    std::lock_guard lock(registry_mutex_);
    sessions_.erase(name);
    throw;
  }
  const SessionSpec& opened = session->spec();
  const std::optional<std::string> journal = session->journal_path();
  const OrderedJson reply{{"type", "session_opened"},
                          {"session", name},
                          {"vehicle", vehicle.name},
                          {"map", opened.map.empty() ? OrderedJson(nullptr) : OrderedJson(opened.map)},
                          {"filter", opened.filter.empty() ? OrderedJson(nullptr) : OrderedJson(opened.filter)},
                          {"filter_source", std::string(localization::FilterSourceName(session_filter.source))},
                          {"wheels", opened.header.wheels},
                          {"ultrasonic", opened.header.ultrasonic},
                          {"origin", formats::ndjson::OriginJson(opened.header.origin)},
                          {"reorder_window_s", opened.reorder_window_s},
                          {"period_s", opened.period_s},
                          {"journal", journal ? OrderedJson(*journal) : OrderedJson(nullptr)},
                          {"resumed", false}};
  std::size_t open = 0;
  {
    std::lock_guard lock(registry_mutex_);
    sessions_[name] = std::move(session);
    open = sessions_.size();
  }
  spdlog::info("session {} opened ({} sessions)", name, open);
  return reply;
}

Dispatcher::OrderedJson Dispatcher::CloseSession(const Json& request) {
  const std::string name = RequiredString(request, "session");
  std::shared_ptr<ServiceSession> session;
  {
    std::lock_guard lock(registry_mutex_);
    const auto it = sessions_.find(name);
    if (it == sessions_.end() || !it->second) Fail(ErrorCode::kUnknownSession, "session '" + name + "' is not open");
    session = it->second;
    sessions_.erase(it);
  }
  const std::optional<std::string> journal = session->Close();
  spdlog::info("session {} closed", name);
  return OrderedJson{{"type", "session_closed"},
                     {"session", name},
                     {"messages", session->accepted()},
                     {"rejected", session->rejected()},
                     {"journal", journal ? OrderedJson(*journal) : OrderedJson(nullptr)}};
}

void Dispatcher::Subscribe(ClientContext& client, const Json& request, const Json& id) {
  const std::shared_ptr<ServiceSession> session = Session(request);
  const std::string stream = OptionalString(request, "stream").value_or("state");
  if (stream != "state" && stream != "estimates" && stream != "live") {
    Fail(ErrorCode::kInvalidField, "stream: must be \"state\", \"estimates\" or \"live\", got '" + stream + "'");
  }
  const double rate_hz = OptionalNumber(request, "rate_hz", 0.0, 0.0, 1e6);
  const StreamKind kind =
      stream == "state" ? StreamKind::kState : (stream == "live" ? StreamKind::kLive : StreamKind::kEstimates);
  session->Subscribe(client.sink, kind, rate_hz,
                     [&](std::size_t subscribers) {
                       return OrderedJson{{"type", "subscribed"}, {"id", id},
                                          {"session", session->name()}, {"stream", stream},
                                          {"rate_hz", rate_hz}, {"subscribers", subscribers}}
                           .dump(-1, ' ', false, Json::error_handler_t::replace);
                     });
}

Dispatcher::OrderedJson Dispatcher::ListMaps() {
  OrderedJson maps = OrderedJson::array();
  for (const std::string& name : ListNamedFiles(settings_.maps_dir, ".geojson")) {
    try {
      const std::shared_ptr<const geometry::RowMap> map = LoadMap(name);
      maps.push_back({{"name", name}, {"rows", map->rows.size()}, {"segments", map->SegmentCount()}});
    } catch (const ServiceError& e) {
      maps.push_back({{"name", name}, {"error", e.what()}});
    }
  }
  return OrderedJson{{"type", "maps"}, {"maps", maps}};
}

Dispatcher::OrderedJson Dispatcher::ListVehicles() {
  OrderedJson vehicles = OrderedJson::array();
  for (const std::string& name : ListNamedFiles(settings_.vehicles_dir, ".json")) {
    try {
      const mapio::VehicleConfig vehicle =
          mapio::LoadVehicleConfig(ResolveNamedFile(settings_.vehicles_dir, name, ".json", ErrorCode::kUnknownVehicle,
                                                    "vehicle"));
      OrderedJson wheels = OrderedJson::array(), rangers = OrderedJson::array();
      for (const auto& wheel : vehicle.wheels) wheels.push_back(wheel.name);
      for (const auto& ranger : vehicle.ultrasonic) rangers.push_back(ranger.name);
      vehicles.push_back({{"name", name},
                          {"kind", mapio::VehicleKindName(vehicle.kind)},
                          {"wheels", wheels},
                          {"ultrasonic", rangers}});
    } catch (const std::exception& e) {
      vehicles.push_back({{"name", name}, {"error", e.what()}});
    }
  }
  return OrderedJson{{"type", "vehicles"}, {"vehicles", vehicles}};
}

Dispatcher::OrderedJson Dispatcher::ListSessions() const {
  std::vector<std::shared_ptr<ServiceSession>> sessions;
  {
    std::lock_guard lock(registry_mutex_);
    for (const auto& [name, session] : sessions_) {
      if (session) sessions.push_back(session);
    }
  }
  OrderedJson list = OrderedJson::array();
  for (const auto& session : sessions) list.push_back(session->Summary());
  return OrderedJson{{"type", "sessions"}, {"sessions", list}};
}

Dispatcher::OrderedJson Dispatcher::Stats() const {
  OrderedJson rejects = OrderedJson::object();
  for (const ErrorCode code : kAllErrorCodes) {
    const std::uint64_t n = stats_.rejects[static_cast<std::size_t>(code)].load();
    if (n > 0) rejects[std::string(ErrorCodeName(code))] = n;
  }
  const LatencyHistogram& latency = stats_.latency;
  return OrderedJson{
      {"type", "stats"},
      {"uptime_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count()},
      {"connections", stats_.connections.load()},
      {"connections_total", stats_.connections_total.load()},
      {"sessions", session_count()},
      {"lines", stats_.lines.load()},
      {"messages", stats_.sensor_messages.load()},
      {"rejects", rejects},
      {"latency_us",
       {{"p50", latency.Quantile(0.5)},
        {"p90", latency.Quantile(0.9)},
        {"p99", latency.Quantile(0.99)},
        {"max", latency.max_us()},
        {"count", latency.count()}}},
      {"dropped_states", stats_.dropped_lines.load()},
      {"queue_high_water_lines", stats_.queue_high_water_lines.load()}};
}

std::size_t Dispatcher::ResumeJournals(std::vector<std::string>& problems) {
  if (settings_.journal_dir.empty()) return 0;
  std::size_t resumed = 0;
  for (const std::string& name : SessionJournal::OpenSessions(settings_.journal_dir)) {
    try {
      const std::string metadata = mapio::ReadInputFile(SessionJournal::MetadataPath(settings_.journal_dir, name),
                                                        kMaxSessionMetadataBytes, "session metadata");
      if (mapio::JsonNestedDeeperThan(metadata, kMaxNestingDepth)) {
        throw std::runtime_error("session metadata nested deeper than " + std::to_string(kMaxNestingDepth) + " levels");
      }
      const Json j = Json::parse(metadata, nullptr, false);
      if (j.is_discarded()) throw std::runtime_error("session metadata is not JSON");
      std::size_t truncated = 0;
      std::unique_ptr<SessionJournal> journal =
          SessionJournal::Reopen(settings_.journal_dir, name, settings_.max_journal_bytes, settings_.fsync, truncated);
      if (truncated > 0) problems.push_back(name + ": cut an unterminated last line of " + std::to_string(truncated) +
                                            " bytes (never acknowledged)");
      std::ifstream in(journal->path(), std::ios::binary);
      const std::string source = journal->path().string();
      std::shared_ptr<ServiceSession> session = BuildSession(SessionSpec::FromJson(j), std::move(journal));
      // Lines of at most kMaxLineBytesLimit (what any max_line_bytes lets in), never held longer.
      formats::BoundedLineReader lines(in, kMaxLineBytesLimit);
      std::string line;
      std::size_t messages = 0;
      for (;;) {
        const formats::BoundedLineReader::Result result = lines.Read(line);
        if (result == formats::BoundedLineReader::Result::kEnd) break;
        const std::string where = source + ":" + std::to_string(lines.line_number());
        if (result == formats::BoundedLineReader::Result::kReadError) throw std::runtime_error(source + ": read error");
        if (result == formats::BoundedLineReader::Result::kTooLong) {
          throw std::runtime_error(where + ": line longer than " + mapio::ByteCountText(kMaxLineBytesLimit) +
                                   " (the largest max_line_bytes)");
        }
        if (result == formats::BoundedLineReader::Result::kUnterminated) {
          throw std::runtime_error(where + ": line not terminated by a newline");
        }
        if (lines.line_number() == 1 || line.empty()) continue;  // the header (the session's spec has it)
        session->Submit(line, formats::ParseSensorMessage(line, session->header(), source, lines.line_number()), false);
        ++messages;
      }
      std::lock_guard lock(registry_mutex_);
      sessions_[name] = std::move(session);
      ++resumed;
      spdlog::info("session {} resumed from its journal ({} messages)", name, messages);
    } catch (const std::exception& e) {
      problems.push_back(name + ": not resumed: " + e.what());
    }
  }
  return resumed;
}

void Dispatcher::Tick() {
  std::vector<std::shared_ptr<ServiceSession>> sessions, idle;
  {
    std::lock_guard lock(registry_mutex_);
    for (auto it = sessions_.begin(); it != sessions_.end();) {
      if (!it->second) {
        ++it;
      } else if (settings_.session_idle_timeout_s > 0 && it->second->idle_s() > settings_.session_idle_timeout_s) {
        idle.push_back(it->second);
        it = sessions_.erase(it);
      } else {
        sessions.push_back(it->second);
        ++it;
      }
    }
  }
  for (const auto& session : sessions) {
    try {
      if (settings_.fsync == FsyncPolicy::kInterval) session->FlushJournal(true);
    } catch (const std::exception& e) {
      spdlog::error("session {}: {}", session->name(), e.what());
    }
  }
  for (const auto& session : idle) {
    spdlog::info("session {} closed after {} s without use", session->name(), settings_.session_idle_timeout_s);
    session->Close();
  }
}

void Dispatcher::Shutdown() {
  shutting_down_ = true;
  std::vector<std::shared_ptr<ServiceSession>> sessions;
  {
    std::lock_guard lock(registry_mutex_);
    for (auto it = sessions_.begin(); it != sessions_.end();) {
      if (it->second) {
        sessions.push_back(it->second);
        it = sessions_.erase(it);
      } else {
        ++it;  // being opened: its opener finds the server shutting down
      }
    }
  }
  for (const auto& session : sessions) {
    try {
      session->Close();
      spdlog::info("session {} closed (shutdown)", session->name());
    } catch (const std::exception& e) {
      spdlog::error("session {}: {}", session->name(), e.what());
    }
  }
}

}  // namespace rowloc::service
