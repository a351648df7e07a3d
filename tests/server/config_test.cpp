#include "server/config.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "protocol/vicon/vicon_datastream.h"
#include "support/test_data.h"

namespace skinstream::server {
namespace {

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = test::scratch_path(name);
  std::ofstream(path) << text;
  return path;
}

std::optional<CommandLine> parse(std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), "skinstreamd");
  std::vector<const char*> argv;
  for (const std::string& a : arguments) argv.push_back(a.c_str());
  int exit_code = -1;
  return parse_command_line(static_cast<int>(argv.size()), argv.data(), exit_code);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, ReferenceConfigParsesToTheDefaults) {
  const DaemonConfig config = load_config_file(test::source_path("config/skinstreamd.reference.json"));
  EXPECT_EQ(to_json(config), to_json(DaemonConfig{}));
}

TEST(Config, BadJsonIsAClearError) {
  const std::string path = write_file("bad.json", "{\"http_port\": 80,,}");
  const std::string error = error_of([&] { load_config_file(path); });
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("not valid JSON"), std::string::npos) << error;
}

TEST(Config, UnknownKeysAndWrongTypesAreErrors) {
  const std::string typo = write_file("typo.json", "{\"http_prot\": 80}");
  EXPECT_NE(error_of([&] { load_config_file(typo); }).find("unknown key \"http_prot\""), std::string::npos);
  const std::string wrong = write_file("wrong.json", "{\"http_port\": \"eighty\"}");
  EXPECT_NE(error_of([&] { load_config_file(wrong); }).find("\"http_port\" has the wrong type"), std::string::npos);
  EXPECT_NE(error_of([&] { load_config_file(test::scratch_path("absent.json")); }).find("cannot open"), std::string::npos);
}

TEST(Config, FlagsOverrideTheFile) {
  const std::string path = write_file("base.json", R"({"subject": "a.sks", "http_port": 9000, "sub_port": 9001, "lookahead": 4,
                                                       "replay": "take.c3d", "loop": true})");
  const auto parsed = parse({"--config", path, "--http-port", "0", "--lookahead", "6", "--max-frame-wait-ms", "40"});
  ASSERT_TRUE(parsed);
  EXPECT_EQ(parsed->config.max_frame_wait_ms, 40);
  EXPECT_EQ(parsed->config.subjects, (std::vector<SubjectConfig>{{"", "a.sks"}}));
  EXPECT_EQ(parsed->config.http_port, 0);
  EXPECT_EQ(parsed->config.sub_port, 9001);
  EXPECT_EQ(parsed->config.lookahead, 6);
  EXPECT_TRUE(parsed->config.loop);
  // A source given on the command line replaces the file's.
  const auto vicon = parse({"--config", path, "--vicon", "localhost:801"});
  ASSERT_TRUE(vicon);
  EXPECT_EQ(vicon->config.vicon, "localhost:801");
  EXPECT_TRUE(vicon->config.replay.empty());
  const auto multicast = parse({"--config", path, "--vicon-multicast", "239.255.42.1:44801"});
  ASSERT_TRUE(multicast);
  EXPECT_EQ(multicast->config.vicon_multicast, "239.255.42.1:44801");
  EXPECT_TRUE(multicast->config.replay.empty());
}

TEST(Config, SubjectsAreNamedFilesOnTheCommandLineAndInTheFile) {
  EXPECT_EQ(parse_subject("a.sks"), (SubjectConfig{"", "a.sks"}));
  EXPECT_EQ(parse_subject("Actor1=a.sks"), (SubjectConfig{"Actor1", "a.sks"}));
  EXPECT_EQ(parse_subject("takes/a=b.sks"), (SubjectConfig{"", "takes/a=b.sks"}));  // a '/' first: a file
  EXPECT_EQ(parse_subject("=a.sks"), (SubjectConfig{"", "=a.sks"}));

  const auto two = parse({"--subject", "Actor1=a.sks", "--subject", "Actor2=b.sks", "--replay-subject", "Actor1"});
  ASSERT_TRUE(two);
  EXPECT_EQ(two->config.subjects, (std::vector<SubjectConfig>{{"Actor1", "a.sks"}, {"Actor2", "b.sks"}}));
  EXPECT_EQ(two->config.replay_subject, "Actor1");

  const std::string list = write_file("subjects.json", R"({"subjects": [{"name": "Actor1", "file": "a.sks"}, "Actor2=b.sks"]})");
  EXPECT_EQ(load_config_file(list).subjects, (std::vector<SubjectConfig>{{"Actor1", "a.sks"}, {"Actor2", "b.sks"}}));
  const std::string one = write_file("subject.json", R"({"subject": "Actor1=a.sks"})");
  EXPECT_EQ(load_config_file(one).subjects, (std::vector<SubjectConfig>{{"Actor1", "a.sks"}}));
  // The command line replaces the file's subjects; the effective list prints and reads back.
  const auto replaced = parse({"--config", list, "--subject", "c.sks"});
  ASSERT_TRUE(replaced);
  EXPECT_EQ(replaced->config.subjects, (std::vector<SubjectConfig>{{"", "c.sks"}}));
  DaemonConfig round_trip;
  apply_json(to_json(load_config_file(list)), round_trip, "printed");
  EXPECT_EQ(round_trip.subjects, load_config_file(list).subjects);
}

TEST(Config, SubjectMistakesAreClearErrors) {
  EXPECT_NE(error_of([] { parse({"--subject", "a.sks", "--subject", "Actor2=b.sks"}); }).find("each follows a named one"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse({"--subject", "Actor1=a.sks", "--subject", "Actor1=b.sks"}); }).find("\"Actor1\" is given twice"),
            std::string::npos);
  EXPECT_NE(error_of([] { parse({"--subject", "Actor1="}); }).find("has no file"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--subject", std::string(300, 'n') + "=a.sks"}); }).find("at most 256 bytes"), std::string::npos);
  const std::string both = write_file("both.json", R"({"subject": "a.sks", "subjects": []})");
  EXPECT_NE(error_of([&] { load_config_file(both); }).find("not both"), std::string::npos);
  const std::string typo = write_file("subject_typo.json", R"({"subjects": [{"name": "A", "fiel": "a.sks"}]})");
  EXPECT_NE(error_of([&] { load_config_file(typo); }).find("unknown key \"fiel\" in a subject"), std::string::npos);
  const std::string number = write_file("subject_number.json", R"({"subjects": [7]})");
  EXPECT_NE(error_of([&] { load_config_file(number); }).find("a subject is"), std::string::npos);
}

TEST(Config, DeformCpusAndSpinLeadComeFromFileAndFlags) {
  const std::string path = write_file("deform.json", R"({"deform_cpus": "off", "deform_spin_lead_us": 0})");
  const auto from_file = parse({"--config", path});
  ASSERT_TRUE(from_file);
  EXPECT_EQ(from_file->config.deform_cpus, "off");
  EXPECT_EQ(from_file->config.deform_spin_lead_us, 0);
  const auto flags = parse({"--config", path, "--deform-cpus", "2,3", "--deform-spin-lead-us", "1500"});
  ASSERT_TRUE(flags);
  EXPECT_EQ(flags->config.deform_cpus, "2,3");
  EXPECT_EQ(flags->config.deform_spin_lead_us, 1500);
}

TEST(Config, PublishThreadsComeFromFileAndFlags) {
  EXPECT_EQ(DaemonConfig{}.publish_threads, 2);
  const std::string path = write_file("publish.json", R"({"publish_threads": 0})");
  const auto from_file = parse({"--config", path});
  ASSERT_TRUE(from_file);
  EXPECT_EQ(from_file->config.publish_threads, 0);
  const auto flags = parse({"--config", path, "--publish-threads", "3"});
  ASSERT_TRUE(flags);
  EXPECT_EQ(flags->config.publish_threads, 3);
  EXPECT_NE(error_of([] { parse({"--publish-threads", "-1"}); }).find("publish_threads"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--publish-threads", "17"}); }).find("publish_threads"), std::string::npos);
}

TEST(Config, SubscriberTcpCongestionComesFromFileAndFlags) {
  EXPECT_EQ(DaemonConfig{}.subscriber_tcp_congestion, "reno");
  const std::string path = write_file("congestion.json", R"({"subscriber_tcp_congestion": "cubic"})");
  const auto from_file = parse({"--config", path});
  ASSERT_TRUE(from_file);
  EXPECT_EQ(from_file->config.subscriber_tcp_congestion, "cubic");
  const auto system_default = parse({"--config", path, "--subscriber-tcp-congestion", ""});
  ASSERT_TRUE(system_default);
  EXPECT_EQ(system_default->config.subscriber_tcp_congestion, "");
  for (const char* bad : {"Reno", "re no", "a_name_too_long_16"})
    EXPECT_NE(error_of([&] { parse({"--subscriber-tcp-congestion", bad}); }).find("subscriber_tcp_congestion must be"), std::string::npos)
        << bad;
}

TEST(Config, SourceLimitsDefaultToTheDecodersAndComeFromTheFile) {
  const DaemonConfig defaults;
  const vicon::DescriptionLimits decoder;
  EXPECT_EQ(defaults.source_max_subjects, static_cast<int>(decoder.max_subjects));
  EXPECT_EQ(defaults.source_max_markers_per_subject, static_cast<int>(decoder.max_markers_per_subject));
  EXPECT_EQ(defaults.source_max_name_bytes, static_cast<int>(decoder.max_name_bytes));
  const std::string path = write_file("limits.json", R"({"source_max_subjects": 4, "source_max_markers_per_subject": 400,
                                                         "source_max_name_bytes": 32})");
  const auto parsed = parse({"--config", path});
  ASSERT_TRUE(parsed);
  EXPECT_EQ(parsed->config.source_max_subjects, 4);
  EXPECT_EQ(parsed->config.source_max_markers_per_subject, 400);
  EXPECT_EQ(parsed->config.source_max_name_bytes, 32);
  for (const char* bad : {R"({"source_max_subjects": 0})", R"({"source_max_markers_per_subject": 65537})", R"({"source_max_name_bytes": -1})"}) {
    const std::string bad_path = write_file("bad_limits.json", bad);
    EXPECT_NE(error_of([&] { parse({"--config", bad_path}); }).find("source_max_"), std::string::npos) << bad;
  }
}

TEST(Config, SubscriberAdmissionComesFromTheFileAndBadNetworksAreNamed) {
  const DaemonConfig defaults;
  EXPECT_TRUE(defaults.allow_subscribers.empty());
  EXPECT_TRUE(defaults.subscriber_token.empty());
  EXPECT_EQ(defaults.subscriber_unsent_kb, 128);
  const std::string path = write_file("admission.json", R"({"max_subscribers": 8, "max_subscribers_per_address": 2,
      "subscriber_write_stall_ms": 3000, "allow_subscribers": ["10.0.0.0/8", "fd00::/8"], "subscriber_token": "t",
      "subscriber_unsent_kb": 64})");
  const auto parsed = parse({"--config", path});
  ASSERT_TRUE(parsed);
  EXPECT_EQ(parsed->config.max_subscribers, 8);
  EXPECT_EQ(parsed->config.max_subscribers_per_address, 2);
  EXPECT_EQ(parsed->config.subscriber_write_stall_ms, 3000);
  EXPECT_EQ(parsed->config.allow_subscribers, (std::vector<std::string>{"10.0.0.0/8", "fd00::/8"}));
  EXPECT_EQ(parsed->config.subscriber_token, "t");
  EXPECT_EQ(parsed->config.subscriber_unsent_kb, 64);
  const std::pair<const char*, const char*> bad[] = {
      {R"({"subscriber_unsent_kb": -1})", "subscriber_unsent_kb must be 0-1048576"},
      {R"({"allow_subscribers": ["10.0.0.0/40"]})", "allow_subscribers: \"10.0.0.0/40\" is not a network"},
      {R"({"allow_subscribers": "10.0.0.0/8"})", "\"allow_subscribers\" has the wrong type"},
      {R"({"max_subscribers": -1})", "max_subscribers must be >= 0"},
      {R"({"subscriber_write_stall_ms": -5})", "subscriber_write_stall_ms must be >= 0"}};
  for (const auto& [json, message] : bad) {
    const std::string bad_path = write_file("bad_admission.json", json);
    EXPECT_NE(error_of([&] { parse({"--config", bad_path}); }).find(message), std::string::npos) << json;
  }
}

// --print-config shows that a token is set, never the token.
TEST(Config, ThePrintedConfigurationHidesTheToken) {
  const std::string path = write_file("token.json", R"({"subscriber_token": "stage-secret-42"})");
  const auto parsed = parse({"--config", path, "--print-config"});
  ASSERT_TRUE(parsed);
  const std::string printed = printable(parsed->config).dump(2);
  EXPECT_EQ(printed.find("stage-secret-42"), std::string::npos) << printed;
  EXPECT_EQ(printable(parsed->config)["subscriber_token"], "(set, 15 bytes, not shown)");
  EXPECT_EQ(printable(parsed->config)["max_subscribers"], 256) << "the rest as it is";
  EXPECT_EQ(printable(DaemonConfig{})["subscriber_token"], "") << "none set: nothing to hide";
}

TEST(Config, OutOfRangeValuesAndConflictsAreErrors) {
  EXPECT_NE(error_of([] { parse({"--deform-threads", "0"}); }).find("deform_threads"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--deform-cpus", "1;2"}); }).find("deform_cpus must be"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--deform-cpus", "1,1"}); }).find("names a CPU twice"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--deform-spin-lead-us", "-5"}); }).find("deform_spin_lead_us"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--max-frame-wait-ms", "-1"}); }).find("max_frame_wait_ms"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--http-port", "70000"}); }).find("http_port"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--replay", "a.c3d", "--vicon", "h:1"}); }).find("one source"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--vicon", "h:1", "--vicon-multicast", "239.1.1.1:44801"}); }).find("one source"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--vicon-multicast", "239.1.1.1"}); }).find("GROUP:PORT"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--log-level", "loud"}); }).find("log_level"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--vicon", "nohost"}); }).find("HOST:PORT"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--qtm", "h", "--natnet", "h"}); }).find("one source"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--vicon", "h:1", "--qtm", "h"}); }).find("one source"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--qtm", "h:99999"}); }).find("qtm must be HOST or HOST:PORT"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--natnet", "h:x"}); }).find("natnet must be HOST or HOST:PORT"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--natnet", "h", "--natnet-interface", "eth0"}); }).find("natnet_interface"),
            std::string::npos);
}

TEST(Config, QtmAndNatNetTakeAHostWithOrWithoutItsPort) {
  const auto qtm = parse({"--qtm", "qtm-pc"});
  ASSERT_TRUE(qtm);
  EXPECT_EQ(qtm->config.qtm, "qtm-pc");
  EXPECT_EQ(parse_host_with_port(qtm->config.qtm, 22223)->port, 22223);
  const auto natnet = parse({"--natnet", "10.0.0.5:1600", "--natnet-interface", "10.0.0.9"});
  ASSERT_TRUE(natnet);
  EXPECT_EQ(parse_host_with_port(natnet->config.natnet, 1510)->port, 1600);
  EXPECT_EQ(natnet->config.natnet_interface, "10.0.0.9");
  EXPECT_FALSE(parse_host_with_port("", 1510));
}

TEST(Config, MulticastIsOffByDefaultAndComesFromFileAndFlags) {
  EXPECT_EQ(DaemonConfig{}.multicast, "");
  EXPECT_EQ(DaemonConfig{}.multicast_ttl, 1);
  const std::string path = write_file("multicast.json", R"({"multicast": "239.1.2.3:9500", "multicast_ttl": 4})");
  const auto from_file = parse({"--config", path});
  ASSERT_TRUE(from_file);
  EXPECT_EQ(from_file->config.multicast, "239.1.2.3:9500");
  EXPECT_EQ(from_file->config.multicast_ttl, 4);
  const auto flags = parse({"--config", path, "--multicast", "239.9.9.9:9600", "--multicast-interface", "10.0.0.2", "--multicast-ttl", "2"});
  ASSERT_TRUE(flags);
  EXPECT_EQ(flags->config.multicast, "239.9.9.9:9600");
  EXPECT_EQ(flags->config.multicast_interface, "10.0.0.2");
  EXPECT_EQ(flags->config.multicast_ttl, 2);
  for (const char* bad : {"10.0.0.1:9500", "239.1.2.3", "239.1.2.3:0", "stage-group:9500"})
    EXPECT_NE(error_of([&] { parse({"--multicast", bad}); }).find("multicast must be GROUP:PORT"), std::string::npos) << bad;
  EXPECT_NE(error_of([] { parse({"--multicast-interface", "eth0"}); }).find("multicast_interface"), std::string::npos);
  EXPECT_NE(error_of([] { parse({"--multicast-ttl", "256"}); }).find("multicast_ttl"), std::string::npos);
  // The offer goes to the next port: on by default, off with 0, and none after port 65535.
  EXPECT_EQ(DaemonConfig{}.multicast_offer_mbit, 20);
  const auto no_offer = parse({"--multicast", "239.1.2.3:65535", "--multicast-offer-mbit", "0"});
  ASSERT_TRUE(no_offer);
  EXPECT_EQ(no_offer->config.multicast_offer_mbit, 0);
  EXPECT_NE(error_of([] {
              parse({"--multicast", "239.1.2.3:65535"});
            }).find("leaves none"),
            std::string::npos);
}

TEST(Config, PrintConfigIsAFlag) {
  const auto parsed = parse({"--print-config", "--sub-port", "1234"});
  ASSERT_TRUE(parsed);
  EXPECT_TRUE(parsed->print_config);
  EXPECT_EQ(to_json(parsed->config)["sub_port"], 1234);
}

}  // namespace
}  // namespace skinstream::server
