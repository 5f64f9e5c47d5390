// The service's requests and every error code, through the dispatcher (no sockets): replies name
// their request, every failure is one error line with its code, and the connection and the session
// go on after each (docs/service.md).
#include "rowloc/service/dispatcher.hpp"

#include "dispatcher_test_support.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <sys/stat.h>

#include <cmath>
#include <fstream>

namespace rowloc::service::test {
namespace {

using nlohmann::json;

class DispatcherTest : public ::testing::Test {
 protected:
  std::unique_ptr<Dispatcher> dispatcher_ = std::make_unique<Dispatcher>(SourceTreeSettings());
};

/// Expects one error line with this code, then that the connection still answers hello.
void ExpectError(TestClient& client, const std::string& line, const std::string& code,
                 const nlohmann::json& then = {{"type", "hello"}, {"id", "after"}}) {
  const std::vector<std::string> replies = client.SendRaw(line);
  ASSERT_EQ(replies.size(), 1u) << line;
  const json reply = json::parse(replies.front());
  EXPECT_EQ(reply["type"], "error") << replies.front();
  EXPECT_EQ(reply["code"], code) << replies.front();
  EXPECT_FALSE(reply["message"].get<std::string>().empty());
  EXPECT_TRUE(reply.contains("id") && reply.contains("line"));
  EXPECT_EQ(client.Send(then)["type"], then["type"]) << "connection broken by " << line;
}

TEST_F(DispatcherTest, HelloNamesProtocolServerAndLimits) {
  TestClient client(*dispatcher_);
  const json reply = client.Send({{"type", "hello"}, {"id", 7}, {"protocol", "rowloc-service/1"}});
  EXPECT_EQ(reply["type"], "hello");
  EXPECT_EQ(reply["id"], 7);
  EXPECT_EQ(reply["protocol"], "rowloc-service/1");
  EXPECT_EQ(reply["sensor_protocol"], "rowloc/1");
  EXPECT_EQ(reply["auth"], "none");
  EXPECT_EQ(reply["limits"]["max_line_bytes"], 1u << 20);
  EXPECT_EQ(client.Send({{"type", "hello"}, {"id", "x"}, {"protocol", "rowloc-service/1.3"}})["type"], "hello");
}

TEST_F(DispatcherTest, MalformedRequestsGetTheirCodes) {
  TestClient client(*dispatcher_);
  ExpectError(client, "{\"type\":", "malformed_json");
  ExpectError(client, "[1,2]", "not_an_object");
  ExpectError(client, "{\"id\":1}", "missing_field");
  ExpectError(client, "{\"type\":3}", "invalid_field");
  ExpectError(client, "{\"type\":\"hello\",\"id\":{\"a\":1}}", "invalid_field");
  ExpectError(client, "{\"type\":\"hello\",\"id\":1e999}", "invalid_field");
  ExpectError(client, "{\"type\":\"launch_rockets\",\"id\":1}", "unknown_type");
  ExpectError(client, "{\"type\":\"hello\",\"protocol\":\"rowloc-service/2\"}", "unsupported_protocol");
  ExpectError(client, "{\"type\":\"get_state\",\"session\":\"nobody\"}", "unknown_session");
  ExpectError(client, "{\"type\":\"imu\",\"session\":\"nobody\",\"t\":0}", "unknown_session");
}

TEST_F(DispatcherTest, ErrorRepliesNameTheRequestIdAndLine) {
  TestClient client(*dispatcher_);
  client.SendRaw("{\"type\":\"hello\"}");
  const json reply = json::parse(client.SendRaw("{\"type\":\"get_state\",\"id\":\"q1\",\"session\":\"x\"}").front());
  EXPECT_EQ(reply["id"], "q1");
  EXPECT_EQ(reply["line"], 2);
  dispatcher_->HandleOversizedLine(client.context(), 3);
  const json oversized = json::parse(client.Take().front());
  EXPECT_EQ(oversized["code"], "line_too_long");
  EXPECT_EQ(oversized["line"], 3);
}

TEST_F(DispatcherTest, OpenSessionRefusesBadNamesAndConfigurations) {
  TestClient client(*dispatcher_);
  const auto open = [](json extra) {
    json request{{"type", "open_session"}, {"id", 1}, {"origin", {{"latitude_deg", 45.0}, {"longitude_deg", 7.0},
                                                                  {"altitude_m", 200.0}}}};
    request.update(extra);
    return request.dump();
  };
  ExpectError(client, open({{"vehicle", "../config/vehicles/differential"}}), "invalid_name");
  ExpectError(client, open({{"vehicle", "/etc/passwd"}}), "invalid_name");
  ExpectError(client, open({{"vehicle", "differential"}, {"session", "../escape"}}), "invalid_name");
  ExpectError(client, open({{"vehicle", "no-such-robot"}}), "unknown_vehicle");
  ExpectError(client, open({{"vehicle", "differential"}, {"map", "atlantis"}}), "unknown_map");
  ExpectError(client, open({{"vehicle", "differential"}, {"filter", "magic"}}), "unknown_filter");
  ExpectError(client, open({{"vehicle_config", {{"name", "broken"}}}}), "invalid_config");
  ExpectError(client, open({{"vehicle_config", "not an object"}}), "invalid_field");
  ExpectError(client, open({{"filter_config", {{"no_such_key", 1}}}, {"vehicle", "differential"}}), "invalid_config");
  ExpectError(client, open(json::object()), "missing_field");
  ExpectError(client, open({{"vehicle", "differential"}, {"reorder_window_s", 99.0}}), "invalid_field");
  ExpectError(client, open({{"vehicle", "differential"}, {"period_s", -1.0}}), "invalid_field");
  ExpectError(client, open({{"vehicle", "differential"}, {"initial_pose", {{"t", 0}}}}), "missing_field");
  ExpectError(client, R"({"type":"open_session","vehicle":"differential"})", "missing_field");  // no origin
  EXPECT_EQ(dispatcher_->session_count(), 0u);
}

/// The differential's vehicle file into DIR/vehicles, and the filter it recommends
/// ("../filters/differential.json") into DIR/filters.
void CopyDifferential(const std::filesystem::path& dir) {
  std::filesystem::copy_file(rowloc::test::SourceDir() / "config/vehicles/differential.json",
                             dir / "vehicles/differential.json");
  std::filesystem::copy_file(rowloc::test::SourceDir() / "config/filters/differential.json",
                             dir / "filters/differential.json");
}

TEST_F(DispatcherTest, NamesThatAreLinksOutOfTheirDirectoryAreRefused) {
  rowloc::test::ScratchDir dir;
  std::filesystem::create_directories(dir / "vehicles");
  std::filesystem::create_directories(dir / "filters");
  CopyDifferential(dir.path());
  std::filesystem::create_symlink(rowloc::test::SourceDir() / "config/vehicles/tracked.json",
                                  dir / "vehicles/outside.json");
  ServiceSettings settings = SourceTreeSettings();
  settings.vehicles_dir = dir / "vehicles";
  Dispatcher dispatcher(settings);
  TestClient client(dispatcher);
  const json origin = {{"latitude_deg", 45.0}, {"longitude_deg", 7.0}, {"altitude_m", 200.0}};
  ExpectError(client, json{{"type", "open_session"}, {"vehicle", "outside"}, {"origin", origin}}.dump(),
              "invalid_name");
  EXPECT_EQ(client.Send({{"type", "open_session"}, {"vehicle", "differential"}, {"origin", origin}})["type"],
            "session_opened");
  const json vehicles = client.Send({{"type", "list_vehicles"}});
  ASSERT_EQ(vehicles["vehicles"].size(), 1u);  // the link is not offered either
  EXPECT_EQ(vehicles["vehicles"][0]["name"], "differential");
}

TEST_F(DispatcherTest, FilesOfItsDirectoriesThatCannotBeReadAreRefusedUnread) {
  // Issue 26: a FIFO or a device in the vehicles, filters or maps directory must not hang or exhaust
  // the server; a file nested a million levels deep must not overflow its stack (dumping the vehicle
  // recursed once per level). Each is refused with invalid_config saying why, and the server goes on.
  rowloc::test::ScratchDir dir;
  for (const char* sub : {"vehicles", "filters", "maps"}) std::filesystem::create_directories(dir / sub);
  CopyDifferential(dir.path());
  ASSERT_EQ(::mkfifo((dir / "vehicles/fifo.json").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir / "filters/fifo.json").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir / "maps/fifo.geojson").c_str(), 0600), 0);
  std::filesystem::create_directories(dir / "vehicles/folder.json");
  std::ofstream(dir / "vehicles/deep.json") << "{\"name\":" << std::string(1000000, '[') << std::string(1000000, ']')
                                            << "}";
  std::ofstream(dir / "vehicles/big.json") << "{}";
  std::filesystem::resize_file(dir / "vehicles/big.json", std::uintmax_t{5} << 20);
  ServiceSettings settings = SourceTreeSettings();
  settings.vehicles_dir = dir / "vehicles";
  settings.filters_dir = dir / "filters";
  settings.maps_dir = dir / "maps";
  Dispatcher dispatcher(settings);
  TestClient client(dispatcher);
  const json origin = {{"latitude_deg", 45.0}, {"longitude_deg", 7.0}, {"altitude_m", 200.0}};
  const auto refusal = [&](const json& names) {
    json request{{"type", "open_session"}, {"origin", origin}};
    request.update(names);
    const std::vector<std::string> replies = client.SendRaw(request.dump());
    EXPECT_EQ(replies.size(), 1u);
    const json reply = replies.empty() ? json() : json::parse(replies.front());
    EXPECT_EQ(reply["code"], "invalid_config") << reply.dump();
    return reply["message"].is_string() ? reply["message"].get<std::string>() : std::string();
  };
  EXPECT_EQ(refusal({{"vehicle", "fifo"}}), "vehicle 'fifo' (fifo.json): is a FIFO (named pipe), not a regular file");
  EXPECT_EQ(refusal({{"vehicle", "differential"}, {"filter", "fifo"}}),
            "filter 'fifo' (fifo.json): is a FIFO (named pipe), not a regular file");
  EXPECT_NE(refusal({{"vehicle", "differential"}, {"map", "fifo"}}).find("is a FIFO (named pipe), not a regular file"),
            std::string::npos);
  EXPECT_EQ(refusal({{"vehicle", "folder"}}), "vehicle 'folder' (folder.json): is a directory, not a regular file");
  EXPECT_EQ(refusal({{"vehicle", "big"}}), "vehicle 'big' (big.json): is larger than the limit of 4 MiB (vehicle file)");
  EXPECT_EQ(refusal({{"vehicle", "deep"}}), "vehicle 'deep': arrays and objects nested deeper than 64 levels");
  // Listed with their errors, not hanging the listing; the good vehicle still opens.
  const json vehicles = client.Send({{"type", "list_vehicles"}});
  ASSERT_EQ(vehicles["vehicles"].size(), 5u) << vehicles.dump();
  for (const json& vehicle : vehicles["vehicles"]) {
    EXPECT_EQ(vehicle.contains("error"), vehicle["name"] != "differential") << vehicle.dump();
  }
  EXPECT_EQ(client.Send({{"type", "list_maps"}})["maps"][0]["name"], "fifo");
  EXPECT_EQ(client.Send({{"type", "open_session"}, {"vehicle", "differential"}, {"origin", origin}})["type"],
            "session_opened");
}

TEST_F(DispatcherTest, SessionsOpenListStreamAndClose) {
  TestClient client(*dispatcher_);
  const json opened = client.Send(OpenTilesSession("tiles"));
  ASSERT_EQ(opened["type"], "session_opened") << opened.dump();
  EXPECT_EQ(opened["id"], 1);
  EXPECT_EQ(opened["wheels"], json({"left_front", "left_rear", "right"}));
  ExpectError(client, OpenTilesSession("tiles").dump(), "session_exists");
  const std::vector<std::string> log = LogLines("agrimaro-tiles-head.ndjson");
  for (std::size_t i = 1; i < log.size(); ++i) EXPECT_TRUE(client.SendRaw(InSession(log[i], "tiles")).empty());
  const json state = client.Send({{"type", "get_state"}, {"id", 2}, {"session", "tiles"}});
  ASSERT_EQ(state["type"], "state");
  ASSERT_TRUE(state["initialised"].get<bool>());
  EXPECT_GT(state["health"]["sensors"]["gnss"]["accepted"].get<int>(), 0);
  EXPECT_LE(state["health"]["pending"].get<int>(), 60);  // 0.2 s of messages held
  Eigen::Matrix3d p;
  for (int i = 0; i < 9; ++i) p(i / 3, i % 3) = state["covariance_xy_phi"][i].get<double>();
  EXPECT_TRUE(p.isApprox(p.transpose()));
  EXPECT_EQ(p.llt().info(), Eigen::Success);
  EXPECT_NEAR(state["ellipse_2sigma"]["semi_major_m"].get<double>(),
              2.0 * std::sqrt(p.topLeftCorner<2, 2>().eigenvalues().real().maxCoeff()), 1e-12);
  EXPECT_EQ(state["slip"].size(), 3u);
  const json sessions = client.Send({{"type", "list_sessions"}});
  ASSERT_EQ(sessions["sessions"].size(), 1u);
  EXPECT_EQ(sessions["sessions"][0]["messages"], log.size() - 1);
  const json closed = client.Send({{"type", "close_session"}, {"session", "tiles"}});
  EXPECT_EQ(closed["type"], "session_closed");
  EXPECT_EQ(closed["messages"], log.size() - 1);
  EXPECT_EQ(dispatcher_->session_count(), 0u);
  ExpectError(client, json{{"type", "get_state"}, {"session", "tiles"}}.dump(), "unknown_session");
}

TEST_F(DispatcherTest, GeneratedSessionNamesAreUnique) {
  TestClient client(*dispatcher_);
  json open = OpenTilesSession("");
  open.erase("session");
  const std::string a = client.Send(open)["session"], b = client.Send(open)["session"];
  EXPECT_NE(a, b);
  EXPECT_EQ(dispatcher_->session_count(), 2u);
}

TEST_F(DispatcherTest, BadSensorMessagesAreRefusedAndTheSessionGoesOn) {
  TestClient client(*dispatcher_);
  client.Send(OpenTilesSession("tiles", 0.0));
  const std::vector<std::string> log = LogLines("agrimaro-tiles-head.ndjson");
  for (std::size_t i = 1; i < 100; ++i) client.SendRaw(InSession(log[i], "tiles"));
  const std::string t = json::parse(log[99])["t"].dump();  // the newest time: bad messages do not move it
  ExpectError(client, R"({"type":"imu","session":"tiles","t":)" + t + R"(,"sensor":"imu","accel_x_mps2":0})",
              "missing_field");
  ExpectError(client, R"({"type":"imu","session":"tiles","t":)" + t + R"(,"sensor":"imu","accel_x_mps2":"a",)"
                      R"("accel_y_mps2":0,"gyro_z_radps":0})", "invalid_field");
  ExpectError(client, R"({"type":"imu","session":"tiles","t":)" + t + R"(,"sensor":"imu","accel_x_mps2":1e999,)"
                      R"("accel_y_mps2":0,"gyro_z_radps":0})", "invalid_field");
  ExpectError(client, R"({"type":"imu","session":"tiles","t":0.001,"sensor":"imu","accel_x_mps2":0,)"
                      R"("accel_y_mps2":0,"gyro_z_radps":0})", "too_old");
  ExpectError(client, R"({"type":"imu","session":"tiles","t":1e9,"sensor":"imu","accel_x_mps2":0,)"
                      R"("accel_y_mps2":0,"gyro_z_radps":0})", "invalid_field");  // a clock jump
  ExpectError(client, R"({"type":"wheels","session":"tiles","t":)" + t + R"(,"speed_radps":{"left_front":500,)"
                      R"("left_rear":1,"right":1}})", "rejected");
  for (std::size_t i = 100; i < log.size(); ++i) EXPECT_TRUE(client.SendRaw(InSession(log[i], "tiles")).empty()) << i;
  const json state = client.Send({{"type", "get_state"}, {"session", "tiles"}});
  EXPECT_TRUE(state["initialised"].get<bool>());
  EXPECT_EQ(state["health"]["rejected_messages"], 1);
  const json stats = client.Send({{"type", "stats"}});
  EXPECT_EQ(stats["rejects"]["too_old"], 1);
  EXPECT_EQ(stats["rejects"]["invalid_field"], 3);
  EXPECT_EQ(stats["rejects"]["rejected"], 1);
  EXPECT_GT(stats["latency_us"]["p99"].get<double>(), 0.0);
}

TEST_F(DispatcherTest, AckOnlyWhenAsked) {
  TestClient client(*dispatcher_);
  client.Send(OpenTilesSession("tiles", 0.0));
  const std::vector<std::string> log = LogLines("agrimaro-tiles-head.ndjson");
  json message = json::parse(InSession(log[1], "tiles"));
  message["id"] = 42;
  const json ack = client.Send(message);
  EXPECT_EQ(ack["type"], "ack");
  EXPECT_EQ(ack["id"], 42);
  EXPECT_EQ(ack["pending"], 0);
}

TEST_F(DispatcherTest, LimitsOnSessionsAndInlineConfigs) {
  ServiceSettings settings = SourceTreeSettings();
  settings.max_sessions = 1;
  settings.max_inline_config_bytes = 1024;
  Dispatcher dispatcher(settings);
  TestClient client(dispatcher);
  EXPECT_EQ(client.Send(OpenTilesSession("a"))["type"], "session_opened");
  ExpectError(client, OpenTilesSession("b").dump(), "limit_exceeded");
  client.Send({{"type", "close_session"}, {"session", "a"}});
  std::ifstream in(rowloc::test::SourceDir() / "config/vehicles/vineyard-ugv-4ws.json");
  json open = OpenTilesSession("c");
  open.erase("vehicle");
  open["vehicle_config"] = json::parse(in);
  open["vehicle_config"]["description"] = std::string(200, 'x');
  ASSERT_GT(open["vehicle_config"].dump().size(), 1024u);
  ExpectError(client, open.dump(), "limit_exceeded");
}

// Found by fuzz/service_dispatch_fuzz.cpp: a header nested 32k levels deep overflowed the stack
// (nlohmann copies and dumps recursively); a 1 MiB line nests up to 500k levels. Lines nested
// deeper than 64 levels are refused before they are parsed.
TEST_F(DispatcherTest, LinesNestedDeeperThan64LevelsAreRefused) {
  TestClient client(*dispatcher_);
  const auto nested = [](std::size_t levels) { return std::string(levels, '[') + std::string(levels, ']'); };
  ExpectError(client, R"({"type":"open_session","vehicle":"differential","header":{"origin":)" + nested(500000) + "}}",
              "limit_exceeded");
  ExpectError(client, R"({"type":"open_session","vehicle_config":{"a":)" + nested(500000) + "}}", "limit_exceeded");
  ExpectError(client, nested(500000), "limit_exceeded");
  // 64 levels, the request object included, pass; brackets inside strings do not count.
  EXPECT_EQ(client.Send(json::parse(R"({"type":"hello","x":)" + nested(63) + "}"))["type"], "hello");
  ExpectError(client, R"({"type":"hello","x":)" + nested(64) + "}", "limit_exceeded");
  EXPECT_EQ(client.Send({{"type", "hello"}, {"client", std::string(1000, '[') + "\\\"{"}})["type"], "hello");
}

TEST_F(DispatcherTest, TokenIsRequiredBeforeAnythingElse) {
  rowloc::test::ScratchDir dir;
  std::ofstream(dir / "token") << "s3cret-token\n";
  ServiceSettings settings = SourceTreeSettings();
  settings.token_file = (dir / "token").string();
  Dispatcher dispatcher(settings);
  TestClient client(dispatcher);
  const json stats{{"type", "stats"}};  // answered with an error: the connection goes on
  const auto expect_unauthorized = [&](TestClient& c, const std::string& line) {
    ExpectError(c, line, "unauthorized", {{"type", "error"}});
    EXPECT_EQ(c.Send(stats)["code"], "unauthorized");
  };
  expect_unauthorized(client, R"({"type":"list_maps"})");
  expect_unauthorized(client, R"({"type":"hello","token":"s3cret-tokeN"})");
  expect_unauthorized(client, R"({"type":"hello","token":"s3cret-token-and-more"})");
  expect_unauthorized(client, R"({"type":"hello"})");
  EXPECT_EQ(client.Send({{"type", "hello"}, {"token", "s3cret-token"}})["auth"], "token");
  EXPECT_EQ(client.Send({{"type", "list_maps"}})["type"], "maps");
  TestClient other(dispatcher, 2);  // authentication is per connection
  expect_unauthorized(other, R"({"type":"list_maps"})");
}

TEST_F(DispatcherTest, ListsMapsAndVehicles) {
  TestClient client(*dispatcher_);
  const json maps = client.Send({{"type", "list_maps"}});
  ASSERT_EQ(maps["maps"].size(), 1u);
  EXPECT_EQ(maps["maps"][0]["name"], "sample-vineyard");
  EXPECT_EQ(maps["maps"][0]["rows"], 10);
  const json vehicles = client.Send({{"type", "list_vehicles"}});
  EXPECT_EQ(vehicles["vehicles"].size(), 5u);
}

TEST(DispatcherShutdown, ClosesEverySessionAndRefusesFurtherRequests) {
  rowloc::test::ScratchDir dir;
  ServiceSettings settings = SourceTreeSettings();
  settings.journal_dir = dir.path();
  Dispatcher dispatcher(settings);
  TestClient client(dispatcher);
  ASSERT_EQ(client.Send(OpenTilesSession("tiles"))["type"], "session_opened");
  dispatcher.Shutdown();
  EXPECT_EQ(dispatcher.session_count(), 0u);
  EXPECT_TRUE(std::filesystem::exists(dir / "closed" / "tiles-1.ndjson"));
  EXPECT_FALSE(std::filesystem::exists(dir / "tiles.ndjson"));  // nothing to resume
  const json reply = json::parse(client.SendRaw(R"({"type":"hello","id":1})").front());
  EXPECT_EQ(reply["code"], "shutting_down");
}

}  // namespace
}  // namespace rowloc::service::test
