// 10^5 hostile but parseable messages into a live session (docs/service.md §7): every one is
// answered or refused, nothing escapes the dispatcher, and the state stays finite with a symmetric
// positive definite covariance throughout.
#include "rowloc/service/dispatcher.hpp"

#include "dispatcher_test_support.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <random>

namespace rowloc::service::test {
namespace {

using nlohmann::json;

/// A value a careless or hostile client might put in a field.
json HostileValue(std::mt19937_64& rng, const json& original) {
  std::uniform_int_distribution<int> kind(0, 11);
  std::normal_distribution<double> normal;
  switch (kind(rng)) {
    case 0: return 1e300;
    case 1: return -1e300;
    case 2: return 1e-300;
    case 3: return 0.0;
    case 4: return original.is_number() ? json(-original.get<double>()) : json(-1.0);
    case 5: return original.is_number() ? json(original.get<double>() * std::pow(10.0, normal(rng) * 6)) : json(normal(rng));
    case 6: return "NaN";
    case 7: return nullptr;
    case 8: return json::array({1, 2});
    case 9: return json::object();
    case 10: return true;
    default: return original.is_number() ? json(original.get<double>() + normal(rng) * 1e3) : json(normal(rng) * 1e6);
  }
}

/// Mutates one leaf of the message (possibly nested), or removes it.
void Mutate(std::mt19937_64& rng, json& message) {
  json* target = &message;
  std::string key;
  for (int depth = 0; depth < 3; ++depth) {
    if (!target->is_object() || target->empty()) break;
    std::uniform_int_distribution<std::size_t> pick(0, target->size() - 1);
    auto it = target->begin();
    std::advance(it, static_cast<std::ptrdiff_t>(pick(rng)));
    key = it.key();
    if (!it->is_object() || std::uniform_int_distribution<int>(0, 1)(rng) == 0) {
      if (std::uniform_int_distribution<int>(0, 9)(rng) == 0) {
        target->erase(key);
      } else if (key == "t" && target == &message) {
        // Times: non-finite or absurd (refused), or a little back (too old); a forward jump
        // within max_time_jump_s would be legal and freeze the session for the test's remainder.
        const json times[] = {1e300, -1e300, "NaN", nullptr, it->get<double>() - 5.0, it->get<double>() + 1e6};
        (*target)[key] = times[std::uniform_int_distribution<int>(0, 5)(rng)];
      } else {
        (*target)[key] = HostileValue(rng, *it);
      }
      return;
    }
    target = &*it;
  }
}

void ExpectHealthyState(const json& state) {
  ASSERT_EQ(state["type"], "state") << state.dump();
  if (!state["initialised"].get<bool>()) return;
  for (const char* key : {"x_m", "y_m", "phi_rad"}) ASSERT_TRUE(std::isfinite(state[key].get<double>())) << key;
  Eigen::Matrix3d p;
  for (int i = 0; i < 9; ++i) {
    ASSERT_TRUE(state["covariance_xy_phi"][i].is_number()) << state.dump();
    p(i / 3, i % 3) = state["covariance_xy_phi"][i].get<double>();
  }
  ASSERT_TRUE(p.allFinite());
  ASSERT_LE((p - p.transpose()).cwiseAbs().maxCoeff(), 1e-9 * p.cwiseAbs().maxCoeff());
  ASSERT_EQ(p.llt().info(), Eigen::Success) << p;
}

TEST(DispatcherHostile, HundredThousandHostileMessagesLeaveAHealthySession) {
  Dispatcher dispatcher(SourceTreeSettings());
  TestClient client(dispatcher);
  ASSERT_EQ(client.Send(OpenTilesSession("s", 0.05))["type"], "session_opened");
  const std::vector<std::string> log = LogLines("agrimaro-tiles-head.ndjson");
  std::vector<json> messages;
  for (std::size_t i = 1; i < log.size(); ++i) messages.push_back(json::parse(InSession(log[i], "s")));
  std::mt19937_64 rng(20261203);
  double time_offset = 0.0;
  std::size_t errors = 0, replies = 0, initialised_checks = 0;
  constexpr std::size_t kMessages = 100000;
  for (std::size_t n = 0; n < kMessages; ++n) {
    const std::size_t index = n % messages.size();
    if (index == 0 && n > 0) time_offset += 1.5;  // the log again, later
    json message = messages[index];
    message["t"] = message["t"].get<double>() + time_offset;
    if (std::uniform_int_distribution<int>(0, 2)(rng) != 0) Mutate(rng, message);
    if (std::uniform_int_distribution<int>(0, 99)(rng) == 0) message["session"] = "other";
    for (const std::string& line : client.SendRaw(message.dump())) {
      ++replies;
      const json reply = json::parse(line);
      ASSERT_TRUE(reply["type"] == "error") << line;
      ASSERT_NE(reply["code"], "internal") << line << " for " << message.dump();
      ++errors;
    }
    if (n % 1000 == 999) {
      const json state = client.Send({{"type", "get_state"}, {"session", "s"}});
      ExpectHealthyState(state);
      initialised_checks += state["initialised"].get<bool>();
    }
  }
  EXPECT_GT(errors, kMessages / 10);  // the hostile ones were refused...
  EXPECT_LT(errors, kMessages);       // ...and the others used
  const json state = client.Send({{"type", "get_state"}, {"session", "s"}});
  ExpectHealthyState(state);
  EXPECT_GE(initialised_checks, 90u);  // of 100: the filter ran (a huge gap re-initialises it)
  EXPECT_EQ(replies, errors);
}

}  // namespace
}  // namespace rowloc::service::test
