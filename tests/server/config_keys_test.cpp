#include "server/config_keys.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "support/test_data.h"

namespace skinstream::server {
namespace {

// A value other than the default for every printed key, each one validate() accepts.
const nlohmann::json kChangedValues = {
    {"subjects", {{{"name", "Actor1"}, {"file", "a.sks"}}, {{"name", "Actor2"}, {"file", "b.sks"}}}},
    {"replay", "take.c3d"},
    {"replay_subject", "Actor1"},
    {"loop", true},
    {"speed", 2.5},
    {"vicon", ""},  // one source at a time: the others stay empty
    {"vicon_pull", true},
    {"vicon_multicast", ""},
    {"qtm", ""},
    {"natnet", ""},
    {"natnet_interface", "10.0.0.9"},
    {"bind_address", "127.0.0.1"},
    {"http_port", 9000},
    {"sub_port", 9001},
    {"web_root", "clients/web"},
    {"ports_file", "ports.json"},
    {"lookahead", 4},
    {"max_frame_wait_ms", 40},
    {"deform_threads", 3},
    {"deform_cpus", "off"},
    {"deform_spin_lead_us", 0},
    {"continuity_seconds", 0.5},
    {"use_pca", false},
    {"default_rate_hz", 240.0},
    {"source_max_subjects", 4},
    {"source_max_markers_per_subject", 400},
    {"source_max_name_bytes", 32},
    {"source_max_coordinate_m", 20.0},
    {"source_handshake_timeout_ms", 5000},
    {"source_stall_ms", 0},
    {"hello_timeout_ms", 500},
    {"subscriber_queue_frames", 8},
    {"compressed_key_interval", 30},
    {"publish_threads", 0},
    {"subscriber_tcp_congestion", "cubic"},
    {"status_interval_ms", 500},
    {"status_log_seconds", 0},
    {"multicast", "239.1.2.3:9500"},
    {"multicast_interface", "10.0.0.2"},
    {"multicast_ttl", 4},
    {"multicast_key_file", "key.txt"},
    {"multicast_offer_mbit", 35},
    {"max_subscribers", 8},
    {"max_subscribers_per_address", 2},
    {"subscriber_write_stall_ms", 3000},
    {"allow_subscribers", {"10.0.0.0/8"}},
    {"subscriber_token", "t"},
    {"max_unauthenticated_subscribers", 6},
    {"max_unauthenticated_per_address", 1},
    {"unauthenticated_hello_timeout_ms", 200},
    {"subscriber_unsent_kb", 64},
    {"subscriber_join_mbit", 500},
    {"record_dir", "takes"},
    {"record_always", true},
    {"record_with_source", true},
    {"record_unlabelled", 16},
    {"control_token_file", "control-token.txt"},
    {"calibration_dir", "calibrations"},
    {"calibration_mesh", "body.obj"},
    {"subject_builder", "/opt/skinstream/bin/skinstream"},
    {"log_level", "debug"}};

// A value out of range, or not of the key's form, for every key that checks its value.
const std::pair<const char*, nlohmann::json> kBadValues[] = {{"speed", 0.0},
                                                             {"vicon", "nohost"},
                                                             {"vicon_multicast", "239.1.1.1"},
                                                             {"qtm", "h:99999"},
                                                             {"natnet", "h:x"},
                                                             {"natnet_interface", "eth0"},
                                                             {"http_port", 70000},
                                                             {"sub_port", -1},
                                                             {"lookahead", 241},
                                                             {"max_frame_wait_ms", 1001},
                                                             {"deform_threads", 0},
                                                             {"deform_cpus", "1;2"},
                                                             {"deform_spin_lead_us", -5},
                                                             {"continuity_seconds", -1.0},
                                                             {"default_rate_hz", 0.0},
                                                             {"source_max_subjects", 0},
                                                             {"source_max_markers_per_subject", 65537},
                                                             {"source_max_name_bytes", -1},
                                                             {"source_max_coordinate_m", 2e6},
                                                             {"source_handshake_timeout_ms", 99},
                                                             {"source_stall_ms", 49},
                                                             {"hello_timeout_ms", -1},
                                                             {"subscriber_queue_frames", 65},
                                                             {"compressed_key_interval", 0},
                                                             {"publish_threads", 17},
                                                             {"subscriber_tcp_congestion", "Reno"},
                                                             {"status_interval_ms", 9},
                                                             {"status_log_seconds", 3601},
                                                             {"multicast", "10.0.0.1:9500"},
                                                             {"multicast_interface", "eth0"},
                                                             {"multicast_ttl", 256},
                                                             {"multicast_offer_mbit", 1001},
                                                             {"max_subscribers", -1},
                                                             {"max_subscribers_per_address", -1},
                                                             {"subscriber_write_stall_ms", -5},
                                                             {"allow_subscribers", {"10.0.0.0/40"}},
                                                             {"subscriber_token", std::string(300, 't')},
                                                             {"record_unlabelled", 1025},
                                                             {"max_unauthenticated_subscribers", -1},
                                                             {"max_unauthenticated_per_address", -1},
                                                             {"unauthenticated_hello_timeout_ms", 9},
                                                             {"subscriber_unsent_kb", -1},
                                                             {"subscriber_join_mbit", -1},
                                                             {"control_token_file", "token\n.txt"},
                                                             {"log_level", "loud"}};

std::optional<CommandLine> parse_flags(std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), "skinstreamd");
  std::vector<const char*> argv;
  for (const std::string& a : arguments) argv.push_back(a.c_str());
  int exit_code = -1;
  return parse_command_line(static_cast<int>(argv.size()), argv.data(), exit_code);
}

std::string config_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// The flag's argument for a JSON value: a string as it is, a number as JSON writes it.
std::string as_argument(const nlohmann::json& value) {
  return value.is_string() ? value.get<std::string>() : value.dump();
}

TEST(ConfigKeys, TheCommittedReferenceIsWhatTheTableMakes) {
  std::ifstream in(test::source_path("config/skinstreamd.reference.json"));
  std::stringstream committed;
  committed << in.rdbuf();
  EXPECT_TRUE(committed.str() == reference_config())
      << "config/skinstreamd.reference.json differs from the key table (server/config_keys.cpp); regenerate "
         "it: "
         "build/bin/skinstreamd --print-reference-config > config/skinstreamd.reference.json";
}

TEST(ConfigKeys, EveryKeyIsNamedOnceAndEveryPrintedKeyIsTested) {
  std::set<std::string> names;
  for (const ConfigKey& key : config_keys()) {
    EXPECT_TRUE(names.insert(key.name).second) << key.name;
    if (key.write) {
      EXPECT_TRUE(kChangedValues.contains(key.name)) << key.name << ": add it to kChangedValues";
    }
    if (key.problem && key.name != "subjects") {
      EXPECT_TRUE(std::any_of(std::begin(kBadValues), std::end(kBadValues),
                              [&](const auto& bad) { return key.name == bad.first; }))
          << key.name << ": add it to kBadValues";
    }
  }
  EXPECT_EQ(to_json(DaemonConfig{}).size(), kChangedValues.size());
}

TEST(ConfigKeys, EveryKeyRoundTripsFromJsonToTheConfigurationAndBack) {
  DaemonConfig defaults_read;
  apply_json(to_json(DaemonConfig{}), defaults_read, "defaults");
  EXPECT_EQ(to_json(defaults_read), to_json(DaemonConfig{}));

  DaemonConfig changed;
  apply_json(kChangedValues, changed, "changed");
  EXPECT_NO_THROW(validate(changed));
  const nlohmann::json printed = to_json(changed);
  for (const auto& [name, value] : kChangedValues.items()) {
    EXPECT_EQ(printed.at(name), value) << name;
    if (value != nlohmann::json("")) {
      EXPECT_NE(printed.at(name), to_json(DaemonConfig{}).at(name))
          << name << ": the test's value is the default";
    }
  }
}

TEST(ConfigKeys, TheCommandLineAndTheFileAgreeOnEveryKey) {
  const std::optional<CommandLine> none = parse_flags({});
  ASSERT_TRUE(none);
  EXPECT_EQ(to_json(none->config), to_json(DaemonConfig{}));
  EXPECT_EQ(to_json(load_config_file(test::source_path("config/skinstreamd.reference.json"))),
            to_json(DaemonConfig{}));

  for (const ConfigKey& key : config_keys()) {
    if (key.flag.empty() || key.name == "subjects") continue;
    const nlohmann::json value = kChangedValues.at(key.name).is_string() && kChangedValues.at(key.name) == ""
                                     ? nlohmann::json("h:1")  // a source
                                     : kChangedValues.at(key.name);
    DaemonConfig from_file;
    apply_json({{key.name, value}}, from_file, "one key");
    const std::optional<CommandLine> from_flag =
        value.is_boolean() ? parse_flags({key.flag}) : parse_flags({key.flag, as_argument(value)});
    ASSERT_TRUE(from_flag) << key.flag;
    EXPECT_EQ(to_json(from_flag->config), to_json(from_file)) << key.flag;
  }
  const std::optional<CommandLine> subjects =
      parse_flags({"--subject", "Actor1=a.sks", "--subject", "Actor2=b.sks"});
  ASSERT_TRUE(subjects);
  EXPECT_EQ(to_json(subjects->config)["subjects"], kChangedValues["subjects"]);
}

TEST(ConfigKeys, AValueOutOfRangeIsRefusedWithTheKeysName) {
  for (const auto& [name, value] : kBadValues) {
    DaemonConfig config;
    apply_json({{name, value}}, config, "bad");
    const std::string error = config_error_of([&] { validate(config); });
    EXPECT_NE(error.find(name), std::string::npos) << name << ": " << error;
  }
}

}  // namespace
}  // namespace skinstream::server
