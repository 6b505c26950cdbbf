#include "capture/live/light_controller.h"

#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <stdlib.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

LightState Light(int number, double slant, double tilt) {
  return {number, 36, LightDirection::FromSlantTilt(slant, tilt)};
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ManualLightControllerTest, TellsTheOperatorAndWaitsForEnter) {
  std::istringstream in("\n\n");
  std::ostringstream out;
  ManualLightController controller(in, out);
  controller.SwitchTo(Light(7, 45, 180));
  EXPECT_THAT(out.str(), HasSubstr("light 7 of 36: set slant 45.0 deg, tilt 180.0 deg"));
  EXPECT_THAT(out.str(), HasSubstr("then press Enter"));
  controller.SwitchTo({0, 36, std::nullopt});
  EXPECT_THAT(out.str(), HasSubstr("Switch all lights off"));
  EXPECT_THAT(ErrorOf([&] { controller.SwitchTo(Light(8, 45, 210)); }),
              HasSubstr("input closed while waiting for Enter (light 8 of 36)"));
}

TEST(CommandLightControllerTest, ExpandsThePlaceholders) {
  CommandLightController controller("dome --led {n}/{count} {state} {slant} {tilt} {x} {y} {z}");
  EXPECT_EQ(controller.Expand(Light(3, 90, 90)),
            "dome --led 3/36 on 90.000000 90.000000 0.000000 1.000000 0.000000");
  EXPECT_EQ(controller.Expand({0, 36, std::nullopt}),
            "dome --led 0/36 off 0.000000 0.000000 0.000000 0.000000 0.000000");
}

TEST(CommandLightControllerTest, RunsTheCommandPerLight) {
  testing::TempDir dir;
  CommandLightController controller("echo {n} {state} >> " + (dir / "log").string());
  controller.SwitchTo(Light(1, 30, 0));
  controller.SwitchTo(Light(2, 30, 30));
  controller.SwitchTo({0, 36, std::nullopt});
  EXPECT_EQ(ReadTextFile(dir / "log"), "1 on\n2 on\n0 off\n");
}

TEST(CommandLightControllerTest, RetriesAFailingCommandThenFails) {
  testing::TempDir dir;
  CommandLightController controller("echo try >> " + (dir / "log").string() + "; exit 3",
                                    {std::chrono::milliseconds(2000), 2});
  EXPECT_THAT(ErrorOf([&] { controller.SwitchTo(Light(5, 45, 0)); }),
              HasSubstr("light controller not answering: command `echo try"));
  EXPECT_THAT(ErrorOf([&] { controller.SwitchTo(Light(5, 45, 0)); }),
              HasSubstr("for light 5 of 36 failed: exit status 3 (after 3 attempts)"));
  EXPECT_EQ(ReadTextFile(dir / "log"), "try\ntry\ntry\ntry\ntry\ntry\n");  // 2 x 3 attempts
}

TEST(CommandLightControllerTest, SucceedsWhenARetrySucceeds) {
  testing::TempDir dir;
  const std::string flag = (dir / "flag").string();
  // Fails the first time, succeeds the second.
  CommandLightController controller(
      "if [ -e " + flag + " ]; then exit 0; else touch " + flag + "; exit 1; fi",
      {std::chrono::milliseconds(2000), 1});
  controller.SwitchTo(Light(1, 30, 0));
}

TEST(CommandLightControllerTest, KillsACommandThatHangs) {
  CommandLightController controller("sleep 30", {std::chrono::milliseconds(100), 1});
  const auto start = Clock::now();
  EXPECT_THAT(ErrorOf([&] { controller.SwitchTo(Light(2, 30, 30)); }),
              HasSubstr("did not finish within 100 ms (killed) (after 2 attempts)"));
  EXPECT_LT(Clock::now() - start, std::chrono::seconds(3));
}

// A dome controller on the other end of a pseudo-terminal: answers each line with `answer(line)`
// (nullopt: no answer).
class FakeDome {
 public:
  explicit FakeDome(std::function<std::optional<std::string>(const std::string&)> answer)
      : answer_(std::move(answer)) {
    master_ = posix_openpt(O_RDWR | O_NOCTTY);
    EXPECT_GE(master_, 0);
    grantpt(master_);
    unlockpt(master_);
    port_ = ptsname(master_);
    thread_ = std::thread([this] { Serve(); });
  }
  ~FakeDome() {
    stop_ = true;
    thread_.join();
    close(master_);
  }
  const std::string& port() const { return port_; }
  std::vector<std::string> lines() {
    std::lock_guard lock(mutex_);
    return lines_;
  }

 private:
  void Serve() {
    std::string pending;
    while (!stop_) {
      pollfd request{master_, POLLIN, 0};
      if (poll(&request, 1, 10) <= 0 || !(request.revents & POLLIN)) continue;
      char buffer[256];
      const ssize_t n = read(master_, buffer, sizeof buffer);
      if (n <= 0) continue;
      pending.append(buffer, n);
      for (auto end = pending.find('\n'); end != std::string::npos; end = pending.find('\n')) {
        const std::string line = pending.substr(0, end);
        pending.erase(0, end + 1);
        {
          std::lock_guard lock(mutex_);
          lines_.push_back(line);
        }
        if (auto reply = answer_(line)) {
          const std::string text = *reply;
          EXPECT_EQ(write(master_, text.data(), text.size()), static_cast<ssize_t>(text.size()));
        }
      }
    }
  }

  std::function<std::optional<std::string>(const std::string&)> answer_;
  int master_ = -1;
  std::string port_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<std::string> lines_;
};

SerialOptions FastSerial(int retries = 2) {
  SerialOptions options;
  options.timeout = std::chrono::milliseconds(200);
  options.retries = retries;
  return options;
}

TEST(SerialLightControllerTest, SpeaksTheLineProtocol) {
  FakeDome dome([](const std::string& line) -> std::optional<std::string> {
    // A chatty firmware: a debug line before the answer, CRLF line ends.
    return "# got " + line + "\r\nOK\r\n";
  });
  SerialLightController controller(dome.port(), FastSerial());
  controller.SwitchTo(Light(7, 45, 180));
  controller.SwitchTo({0, 36, std::nullopt});
  controller.SwitchTo(Light(36, 60, 330));
  EXPECT_EQ(dome.lines(), (std::vector<std::string>{"LIGHT 7", "OFF", "LIGHT 36"}));
}

TEST(SerialLightControllerTest, ControllerNotAnsweringIsAnErrorAfterRetries) {
  FakeDome dome([](const std::string&) -> std::optional<std::string> { return std::nullopt; });
  SerialLightController controller(dome.port(), FastSerial(2));
  const auto start = Clock::now();
  EXPECT_THAT(ErrorOf([&] { controller.SwitchTo(Light(4, 30, 90)); }),
              HasSubstr("light controller not answering: no OK to `LIGHT 4` within 200 ms (after "
                        "3 attempts)"));
  EXPECT_GE(Clock::now() - start, std::chrono::milliseconds(550));  // 3 x 200 ms, give or take
  EXPECT_EQ(dome.lines(), (std::vector<std::string>{"LIGHT 4", "LIGHT 4", "LIGHT 4"}));
}

TEST(SerialLightControllerTest, RetriesAfterALostAnswer) {
  std::atomic<int> seen{0};
  FakeDome dome([&](const std::string&) -> std::optional<std::string> {
    if (seen++ == 0) return std::nullopt;  // the first answer is lost
    return "OK\n";
  });
  SerialLightController controller(dome.port(), FastSerial(1));
  controller.SwitchTo(Light(2, 30, 30));
  EXPECT_EQ(seen.load(), 2);
}

TEST(SerialLightControllerTest, AnErrAnswerFailsAtOnce) {
  FakeDome dome(
      [](const std::string&) -> std::optional<std::string> { return "ERR no such LED\n"; });
  SerialLightController controller(dome.port(), FastSerial());
  EXPECT_THAT(ErrorOf([&] { controller.SwitchTo(Light(99, 30, 30)); }),
              HasSubstr("the light controller refused `LIGHT 99`: ERR no such LED"));
  EXPECT_EQ(dome.lines().size(), 1u);
}

TEST(SerialLightControllerTest, PortErrorsNameThePort) {
  EXPECT_THAT(ErrorOf([] { SerialLightController("/dev/ttyNOPE"); }),
              HasSubstr("/dev/ttyNOPE: cannot open the serial port"));
  testing::TempDir dir;
  testing::WriteFile(dir / "file", "x");
  EXPECT_THAT(ErrorOf([&] { SerialLightController(dir / "file"); }),
              HasSubstr("not a serial port"));
  EXPECT_THAT(ErrorOf([] { MakeLightController("serial:/dev/ttyS0,12345", {}, 1); }),
              HasSubstr("unsupported baud rate 12345"));
  EXPECT_THAT(ErrorOf([] { MakeLightController("lamp", {}, 1); }),
              HasSubstr("unknown light controller \"lamp\""));
}

}  // namespace
}  // namespace photomat
