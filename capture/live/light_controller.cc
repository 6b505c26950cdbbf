#include "capture/live/light_controller.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <thread>

#include "core/error.h"

extern char** environ;

namespace photomat {
namespace {

using Clock = std::chrono::steady_clock;

std::string Describe(const LightState& light) {
  if (light.off()) return "all lights off";
  return fmt::format("light {} of {}", light.number, light.count);
}

void ReplaceAll(std::string& text, const std::string& key, const std::string& value) {
  for (std::size_t at = text.find(key); at != std::string::npos;
       at = text.find(key, at + value.size())) {
    text.replace(at, key.size(), value);
  }
}

// Runs `command` through /bin/sh in its own process group; returns a description of the failure,
// or an empty string on exit status 0.
std::string RunOnce(const std::string& command, std::chrono::milliseconds timeout) {
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attributes, 0);
  const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
  pid_t pid = 0;
  const int spawned =
      posix_spawn(&pid, "/bin/sh", nullptr, &attributes, const_cast<char* const*>(argv), environ);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0) return fmt::format("cannot start /bin/sh: {}", std::strerror(spawned));
  const Clock::time_point deadline = Clock::now() + timeout;
  int status = 0;
  while (true) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) return fmt::format("waitpid: {}", std::strerror(errno));
    if (Clock::now() >= deadline) {
      kill(-pid, SIGKILL);  // the shell and whatever it started
      waitpid(pid, &status, 0);
      return fmt::format("did not finish within {} ms (killed)", timeout.count());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  if (WIFEXITED(status)) {
    return WEXITSTATUS(status) == 0 ? "" : fmt::format("exit status {}", WEXITSTATUS(status));
  }
  return fmt::format("killed by signal {}", WIFSIGNALED(status) ? WTERMSIG(status) : -1);
}

speed_t BaudConstant(int baud, const std::filesystem::path& port) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 921600:
      return B921600;
    default:
      throw Error(port, fmt::format("unsupported baud rate {} (9600, 19200, 38400, 57600, 115200, "
                                    "230400, 460800, 921600)",
                                    baud));
  }
}

}  // namespace

void ManualLightController::SwitchTo(const LightState& light) {
  if (light.off()) {
    out_ << "Switch all lights off (dark frame), then press Enter" << std::flush;
  } else {
    const LightDirection& d = *light.direction;
    out_ << fmt::format(
                "light {} of {}: set slant {:.1f} deg, tilt {:.1f} deg (x {:.3f} y {:.3f} z "
                "{:.3f}), then press Enter",
                light.number, light.count, d.SlantDegrees(), d.TiltDegrees(), d.x(), d.y(), d.z())
         << std::flush;
  }
  std::string line;
  if (!std::getline(in_, line)) {
    throw Error("manual light controller: input closed while waiting for Enter (" +
                Describe(light) + ")");
  }
}

CommandLightController::CommandLightController(std::string command_template,
                                               const CommandOptions& options)
    : template_(std::move(command_template)), options_(options) {
  if (template_.empty()) throw Error("light command: empty command template");
}

std::string CommandLightController::name() const { return "command:" + template_; }

std::string CommandLightController::Expand(const LightState& light) const {
  std::string command = template_;
  const bool on = !light.off() && light.direction;
  const auto number = [&](double v) { return fmt::format("{:.6f}", on ? v : 0.0); };
  ReplaceAll(command, "{n}", std::to_string(light.number));
  ReplaceAll(command, "{count}", std::to_string(light.count));
  ReplaceAll(command, "{state}", on ? "on" : "off");
  ReplaceAll(command, "{slant}", number(on ? light.direction->SlantDegrees() : 0.0));
  ReplaceAll(command, "{tilt}", number(on ? light.direction->TiltDegrees() : 0.0));
  ReplaceAll(command, "{x}", number(on ? light.direction->x() : 0.0));
  ReplaceAll(command, "{y}", number(on ? light.direction->y() : 0.0));
  ReplaceAll(command, "{z}", number(on ? light.direction->z() : 0.0));
  return command;
}

void CommandLightController::SwitchTo(const LightState& light) {
  const std::string command = Expand(light);
  std::string failure;
  const int attempts = options_.retries + 1;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    failure = RunOnce(command, options_.timeout);
    if (failure.empty()) return;
  }
  throw Error(
      fmt::format("light controller not answering: command `{}` for {} failed: {} (after "
                  "{} attempts)",
                  command, Describe(light), failure, attempts));
}

SerialLightController::SerialLightController(std::filesystem::path port,
                                             const SerialOptions& options)
    : port_(std::move(port)), options_(options) {
  const speed_t speed = BaudConstant(options_.baud, port_);
  fd_ = ::open(port_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    throw Error(port_, fmt::format("cannot open the serial port: {}", std::strerror(errno)));
  }
  termios settings{};
  if (tcgetattr(fd_, &settings) != 0) {
    const int error = errno;
    ::close(fd_);
    throw Error(port_, fmt::format("not a serial port: {}", std::strerror(error)));
  }
  cfmakeraw(&settings);  // 8 data bits, no parity, no echo, no line editing
  settings.c_cflag |= CLOCAL | CREAD;
  settings.c_cflag &= ~(CSTOPB | CRTSCTS);
  cfsetispeed(&settings, speed);
  cfsetospeed(&settings, speed);
  if (tcsetattr(fd_, TCSANOW, &settings) != 0) {
    const int error = errno;
    ::close(fd_);
    throw Error(port_, fmt::format("cannot configure the serial port: {}", std::strerror(error)));
  }
}

SerialLightController::~SerialLightController() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<std::string> SerialLightController::Exchange(const std::string& command) {
  // Stale input (a late answer to an earlier attempt) must not be taken for this one's.
  tcflush(fd_, TCIFLUSH);
  char discard[256];
  while (::read(fd_, discard, sizeof discard) > 0) {
  }
  std::size_t written = 0;
  const Clock::time_point deadline = Clock::now() + options_.timeout;
  while (written < command.size()) {
    const ssize_t n = ::write(fd_, command.data() + written, command.size() - written);
    if (n > 0) {
      written += static_cast<std::size_t>(n);
    } else if (n < 0 && errno != EAGAIN && errno != EINTR) {
      throw Error(port_, fmt::format("cannot write to the serial port: {}", std::strerror(errno)));
    } else if (Clock::now() >= deadline) {
      return std::nullopt;
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  std::string pending;
  while (true) {
    for (std::size_t end = pending.find('\n'); end != std::string::npos; end = pending.find('\n')) {
      std::string line = pending.substr(0, end);
      pending.erase(0, end + 1);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line == "OK" || line.rfind("ERR", 0) == 0) return line;
    }
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0) return std::nullopt;
    pollfd request{fd_, POLLIN, 0};
    const int ready = ::poll(&request, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno != EINTR) {
      throw Error(port_, fmt::format("poll on the serial port: {}", std::strerror(errno)));
    }
    if (ready <= 0) continue;
    char buffer[256];
    const ssize_t n = ::read(fd_, buffer, sizeof buffer);
    if (n > 0) {
      pending.append(buffer, static_cast<std::size_t>(n));
    } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
      // A USB serial adapter that was unplugged, or the other end closed: wait out the time-out
      // rather than spin.
      std::this_thread::sleep_for(std::min(left, std::chrono::milliseconds(20)));
    }
  }
}

void SerialLightController::SwitchTo(const LightState& light) {
  const std::string command = light.off() ? "OFF\n" : fmt::format("LIGHT {}\n", light.number);
  const int attempts = options_.retries + 1;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    const std::optional<std::string> answer = Exchange(command);
    if (!answer) continue;
    if (*answer == "OK") return;
    throw Error(port_, fmt::format("the light controller refused `{}`: {}",
                                   command.substr(0, command.size() - 1), *answer));
  }
  throw Error(port_, fmt::format("light controller not answering: no OK to `{}` within {} ms "
                                 "(after {} attempts)",
                                 command.substr(0, command.size() - 1), options_.timeout.count(),
                                 attempts));
}

std::unique_ptr<LightController> MakeLightController(const std::string& spec,
                                                     std::chrono::milliseconds timeout,
                                                     int retries) {
  if (spec == "manual") return std::make_unique<ManualLightController>(std::cin, std::cerr);
  if (spec.rfind("command:", 0) == 0) {
    return std::make_unique<CommandLightController>(spec.substr(8),
                                                    CommandOptions{timeout, retries});
  }
  if (spec.rfind("serial:", 0) == 0) {
    std::string port = spec.substr(7);
    SerialOptions options;
    options.timeout = timeout;
    options.retries = retries;
    if (const auto comma = port.rfind(','); comma != std::string::npos) {
      try {
        options.baud = std::stoi(port.substr(comma + 1));
      } catch (const std::exception&) {
        throw Error(fmt::format("light controller \"{}\": the baud rate must be a number", spec));
      }
      port.resize(comma);
    }
    return std::make_unique<SerialLightController>(port, options);
  }
  throw Error(
      fmt::format("unknown light controller \"{}\": expected manual, command:TEMPLATE or "
                  "serial:PORT[,BAUD]",
                  spec));
}

}  // namespace photomat
