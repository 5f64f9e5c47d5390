// Settings of the service: the file's keys, their domains, and the loopback rule (docs/service.md §9-10).
#include "rowloc/service/service_settings.hpp"

#include "test_support.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <fstream>

namespace rowloc::service {
namespace {

std::filesystem::path Write(const rowloc::test::ScratchDir& dir, const std::string& text) {
  const auto path = dir / "settings.json";
  std::ofstream(path) << text;
  return path;
}

TEST(ServiceSettings, DefaultsAreValidAndLoopback) {
  const ServiceSettings s;
  EXPECT_NO_THROW(ValidateServiceSettings(s));
  EXPECT_EQ(s.listen, "127.0.0.1");
  EXPECT_EQ(s.port, 7878);
  EXPECT_EQ(s.fsync, FsyncPolicy::kInterval);
}

TEST(ServiceSettings, FileOverridesEveryKeyItNames) {
  rowloc::test::ScratchDir dir;
  const ServiceSettings s = LoadServiceSettings(Write(dir, R"({"port":0,"threads":4,"fsync":"always",
      "max_queue_lines":64,"slow_client":"disconnect","reorder_window_s":0.5,"journal_dir":"/var/lib/rowloc"})"));
  EXPECT_EQ(s.port, 0);
  EXPECT_EQ(s.threads, 4);
  EXPECT_EQ(s.fsync, FsyncPolicy::kAlways);
  EXPECT_EQ(s.max_queue_lines, 64u);
  EXPECT_EQ(s.slow_client, SlowClientPolicy::kDisconnect);
  EXPECT_EQ(s.reorder_window_s, 0.5);
  EXPECT_EQ(s.journal_dir, "/var/lib/rowloc");
  EXPECT_EQ(s.max_sessions, 1024u);  // untouched
  EXPECT_NO_THROW(ValidateServiceSettings(s));
}

/// Expects the settings file `text` to be refused (at load or validation) with `fragment` in the message.
void ExpectRefused(const rowloc::test::ScratchDir& dir, const std::string& text, const std::string& fragment) {
  try {
    ValidateServiceSettings(LoadServiceSettings(Write(dir, text)));
    ADD_FAILURE() << "accepted " << text;
  } catch (const ServiceSettingsError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(ServiceSettings, BadFilesNameTheirKey) {
  rowloc::test::ScratchDir dir;
  ExpectRefused(dir, R"({"prot":1})", "unknown key \"prot\"");
  ExpectRefused(dir, R"({"port":"80"})", "port");
  ExpectRefused(dir, R"({"port":70000})", "port");
  ExpectRefused(dir, R"({"threads":0})", "threads");
  ExpectRefused(dir, R"({"fsync":"sometimes"})", "fsync");
  ExpectRefused(dir, R"({"max_line_bytes":10})", "max_line_bytes");
  ExpectRefused(dir, R"({"max_queue_lines":-1})", "max_queue_lines");
  ExpectRefused(dir, R"({"reorder_window_s":10})", "reorder_window_s");
  ExpectRefused(dir, R"({"listen":"0.0.0.0"})", "token file");
  ExpectRefused(dir, R"([1])", "JSON object");
  ExpectRefused(dir, R"({"port":)", "not valid JSON");
  EXPECT_THROW(LoadServiceSettings(dir.path()), ServiceSettingsError);  // a directory
  EXPECT_THROW(LoadServiceSettings(dir / "missing.json"), ServiceSettingsError);
}

TEST(ServiceSettings, LiveViewIsOffByDefaultAndItsKeysHaveDomains) {
  rowloc::test::ScratchDir dir;
  EXPECT_EQ(ServiceSettings{}.http_port, -1);
  const ServiceSettings on = LoadServiceSettings(Write(dir, R"({"http_port":0,"live_view_rate_hz":5})"));
  EXPECT_EQ(on.http_port, 0);
  EXPECT_EQ(on.live_view_rate_hz, 5.0);
  EXPECT_NO_THROW(ValidateServiceSettings(on));
  EXPECT_EQ(LoadServiceSettings(Write(dir, R"({"http_port":null})")).http_port, -1);
  ExpectRefused(dir, R"({"http_port":70000})", "http_port");
  ExpectRefused(dir, R"({"http_port":-5})", "http_port");
  ExpectRefused(dir, R"({"http_port":"8080"})", "http_port");
  ExpectRefused(dir, R"({"live_view_rate_hz":0})", "live_view_rate_hz");
  ExpectRefused(dir, R"({"live_view_rate_hz":"fast"})", "live_view_rate_hz");
}

TEST(ServiceSettings, OtherAddressesNeedAToken) {
  ServiceSettings s;
  s.listen = "0.0.0.0";
  EXPECT_THROW(ValidateServiceSettings(s), ServiceSettingsError);
  s.token_file = "/etc/rowloc/token";
  EXPECT_NO_THROW(ValidateServiceSettings(s));
  EXPECT_TRUE(IsLoopbackAddress("127.0.0.1"));
  EXPECT_TRUE(IsLoopbackAddress("127.1.2.3"));
  EXPECT_TRUE(IsLoopbackAddress("::1"));
  EXPECT_FALSE(IsLoopbackAddress("10.0.0.1"));
  EXPECT_FALSE(IsLoopbackAddress("::"));
}

TEST(ServiceSettings, TokenIsTheFirstLineAndMustNotBeEmpty) {
  rowloc::test::ScratchDir dir;
  std::ofstream(dir / "token") << "abc123  \nsecond line\n";
  EXPECT_EQ(ReadToken(dir / "token"), "abc123");
  std::ofstream(dir / "empty") << "\n";
  EXPECT_THROW(ReadToken(dir / "empty"), ServiceSettingsError);
  std::ofstream(dir / "big") << std::string(5000, 'x');
  EXPECT_THROW(ReadToken(dir / "big"), ServiceSettingsError);
}

TEST(ServiceSettings, OnlyRegularSettingsAndTokenFilesAreRead) {
  // Checked on the opened file (mapio::ReadInputFile), saying what the file is; a FIFO without a
  // writer is refused without waiting for one.
  rowloc::test::ScratchDir dir;
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  const auto error_of = [](const auto& read) -> std::string {
    try {
      read();
    } catch (const ServiceSettingsError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_EQ(error_of([&] { LoadServiceSettings(dir / "fifo"); }),
            (dir / "fifo").string() + ": is a FIFO (named pipe), not a regular file");
  EXPECT_EQ(error_of([&] { ReadToken(dir / "fifo"); }),
            (dir / "fifo").string() + ": is a FIFO (named pipe), not a regular file");
  EXPECT_EQ(error_of([] { LoadServiceSettings("/dev/zero"); }), "/dev/zero: is a character device, not a regular file");
  EXPECT_EQ(error_of([&] { LoadServiceSettings(dir.path()); }),
            dir.path().string() + ": is a directory, not a regular file");
  std::ofstream(dir / "big.json") << "{}";
  std::filesystem::resize_file(dir / "big.json", (std::size_t{1} << 20) + 1);
  EXPECT_EQ(error_of([&] { LoadServiceSettings(dir / "big.json"); }),
            (dir / "big.json").string() + ": is larger than the limit of 1 MiB (settings file)");
}

}  // namespace
}  // namespace rowloc::service
