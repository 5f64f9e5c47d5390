// Sessions over time: the reorder window, subscriptions, and the journal that resumes a session
// bit for bit after the server died (docs/service.md §5, §6, §8).
#include "rowloc/service/dispatcher.hpp"
#include "rowloc/service/session_journal.hpp"

#include "dispatcher_test_support.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>

namespace rowloc::service::test {
namespace {

using nlohmann::json;

std::string StateText(TestClient& client, const std::string& session) {
  json state = client.Send({{"type", "get_state"}, {"session", session}});
  return state.dump();
}

/// Streams log lines [begin, end) of the tiles log into a session; returns the lines received.
std::vector<std::string> Stream(TestClient& client, const std::string& session, std::size_t begin, std::size_t end) {
  const std::vector<std::string> log = LogLines("agrimaro-tiles-head.ndjson");
  std::vector<std::string> received;
  for (std::size_t i = begin; i < std::min(end, log.size()); ++i) {
    for (std::string& line : client.SendRaw(InSession(log[i], session))) received.push_back(std::move(line));
  }
  return received;
}

TEST(DispatcherSessions, ReorderWindowUsesALateFixAsIfInOrder) {
  const std::vector<std::string> log = LogLines("agrimaro-tiles-head.ndjson");
  // The second GNSS fix arrives after the messages of the next 0.15 s (equal times keep their
  // arrival order: the fix and the messages of its time that followed it move together).
  std::vector<std::string> late(log.begin() + 1, log.end());
  const auto time_of = [](const std::string& l) { return json::parse(l)["t"].get<double>(); };
  const auto fix = std::find_if(late.begin() + 1, late.end(),
                                [](const std::string& l) { return l.find("\"gps\"") != std::string::npos; });
  ASSERT_NE(fix, late.end());
  const double fix_t = time_of(*fix);
  const auto same_time_end = std::find_if(fix, late.end(), [&](const std::string& l) { return time_of(l) > fix_t; });
  const auto after = std::find_if(fix, late.end(), [&](const std::string& l) { return time_of(l) > fix_t + 0.15; });
  const auto moved = static_cast<std::size_t>(std::distance(fix, same_time_end));
  std::rotate(fix, same_time_end, after);  // the fix's time block now arrives after the next 0.15 s

  Dispatcher reordered(SourceTreeSettings()), in_order(SourceTreeSettings());
  TestClient b(reordered), c(in_order);
  b.Send(OpenTilesSession("s"));
  c.Send(OpenTilesSession("s"));
  for (const std::string& line : late) EXPECT_TRUE(b.SendRaw(InSession(line, "s")).empty()) << line;
  for (std::size_t i = 1; i < log.size(); ++i) c.SendRaw(InSession(log[i], "s"));
  // Same filter input, so the same state to the bit.
  EXPECT_EQ(StateText(b, "s"), StateText(c, "s"));
  const json state = b.Send({{"type", "get_state"}, {"session", "s"}});
  EXPECT_EQ(state["health"]["rejected_messages"], 0);

  // Without a window the late fix is too old.
  Dispatcher strict(SourceTreeSettings());
  TestClient d(strict);
  d.Send(OpenTilesSession("s", 0.0));
  std::size_t too_old = 0;
  for (const std::string& line : late) {
    for (const std::string& reply : d.SendRaw(InSession(line, "s"))) too_old += json::parse(reply)["code"] == "too_old";
  }
  EXPECT_EQ(too_old, moved);
}

TEST(DispatcherSessions, StateSubscriptionAtARate) {
  Dispatcher dispatcher(SourceTreeSettings());
  TestClient client(dispatcher);
  client.Send(OpenTilesSession("s", 0.0));
  EXPECT_EQ(client.Send({{"type", "subscribe"}, {"session", "s"}, {"rate_hz", 10.0}})["type"], "subscribed");
  const std::vector<std::string> pushed = Stream(client, "s", 1, 1000);
  std::vector<double> times;
  for (const std::string& line : pushed) {
    const json state = json::parse(line);
    ASSERT_EQ(state["type"], "state");
    times.push_back(state["t"]);
  }
  ASSERT_GE(times.size(), 14u);  // 1.42 s at 10 Hz
  EXPECT_LE(times.size(), 16u);
  for (std::size_t i = 1; i < times.size(); ++i) EXPECT_GE(times[i] - times[i - 1], 0.1 - 1e-9);
  EXPECT_TRUE(client.Send({{"type", "unsubscribe"}, {"session", "s"}})["was_subscribed"].get<bool>());
  json later = json::parse(InSession(LogLines("agrimaro-tiles-head.ndjson").back(), "s"));
  later["t"] = later["t"].get<double>() + 0.2;
  EXPECT_TRUE(client.SendRaw(later.dump()).empty());  // used, and nothing pushed any more
}

TEST(DispatcherSessions, EstimatesSubscriptionIsTheEstimateStreamWithTheSession) {
  Dispatcher dispatcher(SourceTreeSettings());
  TestClient client(dispatcher);
  client.Send(OpenTilesSession("s", 0.0));
  client.Send({{"type", "subscribe"}, {"session", "s"}, {"stream", "estimates"}});
  const std::vector<std::string> header = client.Take();
  std::vector<std::string> lines = Stream(client, "s", 1, 1000);
  ASSERT_GT(lines.size(), 20u);
  const json first = json::parse(lines.front());
  EXPECT_TRUE(first["type"] == "estimate" || first["type"] == "update");
  for (const std::string& line : lines) {
    EXPECT_NE(line.find(",\"session\":\"s\"}"), std::string::npos);
    EXPECT_EQ(line.back(), '}');
  }
}

TEST(DispatcherSessions, AJournalResumesTheSessionBitForBit) {
  rowloc::test::ScratchDir dir;
  ServiceSettings settings = SourceTreeSettings();
  settings.journal_dir = dir.path();
  std::string state_before;
  {
    Dispatcher first(settings);
    TestClient client(first);
    ASSERT_EQ(client.Send(OpenTilesSession("tiles"))["type"], "session_opened");
    Stream(client, "tiles", 1, 150);
    state_before = StateText(client, "tiles");
    // The dispatcher goes away without Shutdown or close: what a kill -9 leaves (batches flushed).
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "tiles.ndjson"));
  Dispatcher second(settings);
  std::vector<std::string> problems;
  ASSERT_EQ(second.ResumeJournals(problems), 1u);
  EXPECT_TRUE(problems.empty());
  TestClient client(second);
  EXPECT_EQ(StateText(client, "tiles"), state_before);
  Stream(client, "tiles", 150, 1000);

  Dispatcher reference(SourceTreeSettings());
  TestClient uninterrupted(reference);
  uninterrupted.Send(OpenTilesSession("tiles"));
  Stream(uninterrupted, "tiles", 1, 1000);
  EXPECT_EQ(StateText(client, "tiles"), StateText(uninterrupted, "tiles"));

  const json closed = client.Send({{"type", "close_session"}, {"session", "tiles"}});
  EXPECT_EQ(closed["journal"], (dir / "closed" / "tiles-1.ndjson").string());
  EXPECT_TRUE(SessionJournal::OpenSessions(dir.path()).empty());
  Dispatcher third(settings);
  EXPECT_EQ(third.ResumeJournals(problems), 0u);  // closed sessions stay closed
}

/// A journal directory with the session "tiles" left open after 50 messages (as a kill -9 leaves it).
ServiceSettings JournalWithOpenSession(const rowloc::test::ScratchDir& dir) {
  ServiceSettings settings = SourceTreeSettings();
  settings.journal_dir = dir.path();
  Dispatcher first(settings);
  TestClient client(first);
  client.Send(OpenTilesSession("tiles"));
  Stream(client, "tiles", 1, 50);
  return settings;
}

TEST(DispatcherSessions, AnUnterminatedLastJournalLineIsCutOnResume) {
  rowloc::test::ScratchDir dir;
  const ServiceSettings settings = JournalWithOpenSession(dir);
  std::ofstream(dir / "tiles.ndjson", std::ios::app) << R"({"type":"imu","t":9,"sens)";
  Dispatcher second(settings);
  std::vector<std::string> problems;
  EXPECT_EQ(second.ResumeJournals(problems), 1u);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("unterminated"), std::string::npos);
}

/// The problems of resuming the journals of `settings` (none resumed).
std::vector<std::string> ResumeProblems(const ServiceSettings& settings) {
  Dispatcher second(settings);
  std::vector<std::string> problems;
  EXPECT_EQ(second.ResumeJournals(problems), 0u);
  return problems;
}

TEST(DispatcherSessions, AJournalThatIsNotARegularFileIsNotResumed) {
  // Issue 26: a FIFO in the journal's place hung the server's start (it never listened), and
  // /dev/zero took memory until the server was killed (2.2 GB in 5 s).
  rowloc::test::ScratchDir dir;
  const ServiceSettings settings = JournalWithOpenSession(dir);
  std::filesystem::remove(dir / "tiles.ndjson");
  ASSERT_EQ(::mkfifo((dir / "tiles.ndjson").c_str(), 0600), 0);
  std::vector<std::string> problems = ResumeProblems(settings);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0], "tiles: not resumed: " + (dir / "tiles.ndjson").string() +
                             ": the journal is not a regular file (a FIFO, a device or a directory)");
  std::filesystem::remove(dir / "tiles.ndjson");
  std::filesystem::create_symlink("/dev/zero", dir / "tiles.ndjson");
  problems = ResumeProblems(settings);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("the journal is not a regular file"), std::string::npos) << problems[0];
}

TEST(DispatcherSessions, AJournalLineIsReadOnlyUpToTheLargestLineLimit) {
  // A line no server writes (longer than any max_line_bytes) is refused once 64 MiB of it are read,
  // never held whole: the session is not resumed.
  rowloc::test::ScratchDir dir;
  const ServiceSettings settings = JournalWithOpenSession(dir);
  const std::string imu = R"({"type":"imu","t":0.5,"sensor":"imu","accel_x_mps2":0,"accel_y_mps2":0,"gyro_z_radps":0})";
  std::ofstream(dir / "tiles.ndjson", std::ios::app) << imu << std::string(kMaxLineBytesLimit, ' ') << "\n";
  const std::vector<std::string> problems = ResumeProblems(settings);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0], "tiles: not resumed: " + (dir / "tiles.ndjson").string() +
                             ":51: line longer than 64 MiB (the largest max_line_bytes)");
}

TEST(DispatcherSessions, AJournalsMetadataIsBoundedInSizeAndDepth) {
  // Metadata nested a million levels deep overflowed the stack when the session was rebuilt.
  rowloc::test::ScratchDir dir;
  const ServiceSettings settings = JournalWithOpenSession(dir);
  std::ofstream(dir / "tiles.session.json", std::ios::trunc)
      << R"({"session":"tiles","vehicle":"x","vehicle_config":)" << std::string(1000000, '[')
      << std::string(1000000, ']') << "}";
  std::vector<std::string> problems = ResumeProblems(settings);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0], "tiles: not resumed: session metadata nested deeper than 64 levels");
  std::filesystem::resize_file(dir / "tiles.session.json", (std::uintmax_t{128} << 20) + 1);  // sparse
  problems = ResumeProblems(settings);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems[0].find("is larger than the limit of 128 MiB (session metadata)"), std::string::npos)
      << problems[0];
}

TEST(DispatcherSessions, ALongUnterminatedJournalTailIsCutInBlocks) {
  // The cut of an unterminated last line read the journal back one byte per system call: 7 s for a
  // 20 MiB tail, minutes for a journal of max_journal_bytes, before the server listened.
  rowloc::test::ScratchDir dir;
  const ServiceSettings settings = JournalWithOpenSession(dir);
  const std::uintmax_t size = std::filesystem::file_size(dir / "tiles.ndjson");
  std::filesystem::resize_file(dir / "tiles.ndjson", size + (std::uintmax_t{64} << 20));  // 64 MiB of zeros, no "\n"
  Dispatcher second(settings);
  std::vector<std::string> problems;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(second.ResumeJournals(problems), 1u);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0], "tiles: cut an unterminated last line of 67108864 bytes (never acknowledged)");
  EXPECT_EQ(std::filesystem::file_size(dir / "tiles.ndjson"), size);
}

TEST(DispatcherSessions, ClosingAClientEndsItsSubscriptions) {
  Dispatcher dispatcher(SourceTreeSettings());
  TestClient owner(dispatcher, 1);
  owner.Send(OpenTilesSession("s", 0.0));
  {
    TestClient watcher(dispatcher, 2);
    EXPECT_EQ(watcher.Send({{"type", "subscribe"}, {"session", "s"}})["subscribers"], 1);
  }
  const json sessions = owner.Send({{"type", "list_sessions"}});
  EXPECT_EQ(sessions["sessions"][0]["subscribers"], 0);
}

}  // namespace
}  // namespace rowloc::service::test
