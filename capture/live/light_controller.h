#pragma once

#include <chrono>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <string>

#include "capture/live/frame_source.h"

namespace photomat {

// Switches the lights of a capture: a dome's controller, an operator moving a lamp, a script.
// SwitchTo returns once the light is on (or all lights are off for LightState::off()); the
// session then waits its settle time. Failures throw Error naming the controller.
class LightController {
 public:
  virtual ~LightController() = default;
  virtual std::string name() const = 0;
  virtual void SwitchTo(const LightState& light) = 0;
};

// Tells the operator which light to set and waits for Enter:
//   "light 7 of 36: set slant 45.0 deg, tilt 180.0 deg (x -0.707 y 0.000 z 0.707), then press
//   Enter"
// End of input is an Error (nobody is there to move the lamp).
class ManualLightController final : public LightController {
 public:
  ManualLightController(std::istream& in, std::ostream& out) : in_(in), out_(out) {}
  std::string name() const override { return "manual"; }
  void SwitchTo(const LightState& light) override;

 private:
  std::istream& in_;
  std::ostream& out_;
};

struct CommandOptions {
  // A command that has not finished by then is killed (with the processes it started) and the
  // attempt counts as failed.
  std::chrono::milliseconds timeout{10000};
  // Further attempts after a failed one (non-zero exit, time-out).
  int retries = 2;
};

// Runs a user command template through /bin/sh per light, for domes with their own switching
// tool. Placeholders: {n} (1-based light number, 0 = all off), {count}, {state} ("on" / "off"),
// {slant} and {tilt} (degrees), {x} {y} {z} (the direction); off, the angles and vector are 0.
// The command succeeds when it exits with status 0.
class CommandLightController final : public LightController {
 public:
  CommandLightController(std::string command_template, const CommandOptions& options = {});
  std::string name() const override;
  void SwitchTo(const LightState& light) override;
  // The command line for `light` (for messages and tests).
  std::string Expand(const LightState& light) const;

 private:
  std::string template_;
  CommandOptions options_;
};

struct SerialOptions {
  int baud = 115200;
  // Time for the controller to answer one command.
  std::chrono::milliseconds timeout{2000};
  // Further attempts after a time-out or an unreadable answer.
  int retries = 2;
};

// The line protocol over a serial port (README, "Capture"): the host sends "LIGHT <n>\n" (n the
// 1-based light number in the plan) or "OFF\n"; the controller answers "OK\n" once the light is
// on, or "ERR <reason>\n". Lines are ASCII; a CR before the LF is ignored; other lines the
// controller prints (start-up banners, debug output) are skipped. Port: raw 8N1, no flow control.
// Each attempt discards stale input first; after `retries` further attempts without an answer the
// controller is declared not answering. An ERR answer fails at once: the controller said no.
class SerialLightController final : public LightController {
 public:
  // Opens and configures the port; throws Error naming it.
  SerialLightController(std::filesystem::path port, const SerialOptions& options = {});
  ~SerialLightController() override;
  SerialLightController(const SerialLightController&) = delete;
  SerialLightController& operator=(const SerialLightController&) = delete;

  std::string name() const override { return "serial:" + port_.string(); }
  void SwitchTo(const LightState& light) override;

 private:
  // One attempt: nullopt when no OK/ERR line came in time.
  std::optional<std::string> Exchange(const std::string& command);

  std::filesystem::path port_;
  SerialOptions options_;
  int fd_ = -1;
};

// A controller from its command-line form:
//   "manual"                    ManualLightController on standard input/output
//   "command:TEMPLATE"          CommandLightController
//   "serial:PORT[,BAUD]"        SerialLightController
// `timeout` and `retries` apply to command and serial controllers.
std::unique_ptr<LightController> MakeLightController(const std::string& spec,
                                                     std::chrono::milliseconds timeout,
                                                     int retries);

}  // namespace photomat
