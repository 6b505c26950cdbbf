#include "capture/live/v4l2_syscalls.h"

#include <fcntl.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>

namespace photomat {

int LinuxV4l2Syscalls::Open(const char* path, int flags) { return ::open(path, flags); }

int LinuxV4l2Syscalls::Close(int fd) { return ::close(fd); }

int LinuxV4l2Syscalls::Ioctl(int fd, unsigned long request, void* argument) {
  // A signal may interrupt an ioctl before it did anything; the V4L2 ioctls are safe to repeat.
  int result;
  do {
    result = ::ioctl(fd, request, argument);
  } while (result == -1 && errno == EINTR);
  return result;
}

void* LinuxV4l2Syscalls::Mmap(std::size_t length, int protection, int flags, int fd, off_t offset) {
  return ::mmap(nullptr, length, protection, flags, fd, offset);
}

int LinuxV4l2Syscalls::Munmap(void* address, std::size_t length) {
  return ::munmap(address, length);
}

int LinuxV4l2Syscalls::Poll(pollfd* fds, nfds_t count, int timeout_ms) {
  return ::poll(fds, count, timeout_ms);
}

}  // namespace photomat
