// The `live` stream (docs/service.md §5, docs/live-view.md §4): the state lines of the `state`
// stream plus a `gnss` line per fix in the session's local frame, and the live view's scene.
#include "dispatcher_test_support.hpp"
#include "rowloc/mapio/local_frame.hpp"
#include "rowloc/mapio/vehicle_config.hpp"
#include "rowloc/service/live_scene.hpp"

#include <gtest/gtest.h>

namespace rowloc::service {
namespace {

using nlohmann::json;
using test::InSession;
using test::LogLines;
using test::OpenTilesSession;
using test::SourceTreeSettings;
using test::TestClient;

TEST(LiveStream, IsTheStateStreamPlusTheFixesInTheLocalFrame) {
  Dispatcher dispatcher(SourceTreeSettings());
  TestClient feeder(dispatcher, 1), live(dispatcher, 2), states(dispatcher, 3);
  ASSERT_EQ(feeder.Send(OpenTilesSession("s", 0.0))["type"], "session_opened");
  const json subscribed = live.Send({{"type", "subscribe"}, {"session", "s"}, {"stream", "live"}});
  ASSERT_EQ(subscribed["type"], "subscribed") << subscribed;
  EXPECT_EQ(subscribed["stream"], "live");
  ASSERT_EQ(states.Send({{"type", "subscribe"}, {"session", "s"}})["type"], "subscribed");

  const std::vector<std::string> log = LogLines("agrimaro-tiles-head.ndjson");
  const json header = json::parse(log.front());
  const mapio::LocalFrame frame({header["origin"]["latitude_deg"], header["origin"]["longitude_deg"],
                                 header["origin"]["altitude_m"]});
  std::vector<json> fixes_sent;
  for (std::size_t i = 1; i < log.size() && i < 600; ++i) {
    const json message = json::parse(log[i]);
    if (message["type"] == "gps" && message.contains("latitude_deg")) fixes_sent.push_back(message);
    ASSERT_TRUE(feeder.SendRaw(InSession(log[i], "s")).empty()) << log[i];
  }
  ASSERT_FALSE(fixes_sent.empty());

  std::vector<std::string> live_states, state_stream;
  std::vector<json> fixes;
  for (const std::string& line : live.Take()) {
    const json j = json::parse(line);
    if (j["type"] == "state") live_states.push_back(line);
    if (j["type"] == "gnss") fixes.push_back(j);
    EXPECT_TRUE(j["type"] == "state" || j["type"] == "gnss") << line;  // no echoes without rangers
  }
  for (const std::string& line : states.Take()) state_stream.push_back(line);
  EXPECT_EQ(live_states, state_stream);  // the same state lines, byte for byte
  ASSERT_EQ(fixes.size(), fixes_sent.size());
  std::size_t used = 0;
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    const json& sent = fixes_sent[i];
    const Eigen::Vector3d enu = frame.ToEnu(sent["latitude_deg"], sent["longitude_deg"], sent["altitude_m"]);
    EXPECT_EQ(fixes[i]["t"], sent["t"]);
    EXPECT_EQ(fixes[i]["session"], "s");
    EXPECT_EQ(fixes[i]["fix"], sent["fix"]);
    EXPECT_NEAR(fixes[i]["x_m"].get<double>(), enu.x(), 1e-9);
    EXPECT_NEAR(fixes[i]["y_m"].get<double>(), enu.y(), 1e-9);
    EXPECT_EQ(fixes[i]["sigma_m"], sent["sigma_horizontal_m"]);
    if (fixes[i]["accepted"] == true) ++used;
  }
  EXPECT_GT(used, 0u);  // the filter has an initial pose: it updates with the fixes
}

TEST(LiveStream, UnknownStreamsAreStillRefused) {
  Dispatcher dispatcher(SourceTreeSettings());
  TestClient client(dispatcher);
  ASSERT_EQ(client.Send(OpenTilesSession("s"))["type"], "session_opened");
  const json reply = client.Send({{"type", "subscribe"}, {"session", "s"}, {"stream", "video"}});
  EXPECT_EQ(reply["code"], "invalid_field");
  EXPECT_NE(reply["message"].get<std::string>().find("live"), std::string::npos);
}

TEST(LiveScene, HasTheVehicleGeometryAndTheMapRows) {
  Dispatcher dispatcher(SourceTreeSettings());
  TestClient client(dispatcher);
  json open = {{"type", "open_session"}, {"session", "v"}, {"vehicle", "vineyard-ugv-4ws"}, {"map", "sample-vineyard"}};
  ASSERT_EQ(client.Send(open)["type"], "session_opened");
  const std::shared_ptr<ServiceSession> session = dispatcher.FindSession("v");
  const std::shared_ptr<const geometry::RowMap> map = dispatcher.LoadMap("sample-vineyard");
  const json scene = json::parse(LiveSceneLine(*session, map.get(), ""));
  const mapio::VehicleConfig vehicle =
      mapio::LoadVehicleConfig(rowloc::test::SourceDir() / "config/vehicles/vineyard-ugv-4ws.json");
  EXPECT_EQ(scene["type"], "scene");
  EXPECT_EQ(scene["map"], "sample-vineyard");
  EXPECT_TRUE(scene["map_error"].is_null());
  ASSERT_EQ(scene["vehicle"]["wheels"].size(), vehicle.wheels.size());
  for (std::size_t i = 0; i < vehicle.wheels.size(); ++i) {
    EXPECT_EQ(scene["vehicle"]["wheels"][i]["name"], vehicle.wheels[i].name);
    EXPECT_EQ(scene["vehicle"]["wheels"][i]["x_m"], vehicle.wheels[i].position_m.x());
    EXPECT_EQ(scene["vehicle"]["wheels"][i]["radius_m"], vehicle.wheels[i].nominal_radius_m);
  }
  ASSERT_EQ(scene["vehicle"]["ultrasonic"].size(), vehicle.ultrasonic.size());
  EXPECT_EQ(scene["vehicle"]["ultrasonic"][0]["yaw_rad"], vehicle.ultrasonic[0].yaw_rad);
  ASSERT_EQ(scene["rows"].size(), map->rows.size());
  for (std::size_t r = 0; r < map->rows.size(); ++r) {
    EXPECT_EQ(scene["rows"][r]["id"], map->rows[r].id);
    ASSERT_EQ(scene["rows"][r]["points"].size(), map->rows[r].points_m.size());
    EXPECT_EQ(scene["rows"][r]["points"][0][1], map->rows[r].points_m[0].y());
  }
  // Without a map: no rows, and the reason when the map could not be read.
  const json no_map = json::parse(LiveSceneLine(*session, nullptr, "map 'x': unreadable"));
  EXPECT_TRUE(no_map["rows"].empty());
  EXPECT_EQ(no_map["map_error"], "map 'x': unreadable");
}

}  // namespace
}  // namespace rowloc::service
