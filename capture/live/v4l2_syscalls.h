#pragma once

#include <poll.h>
#include <sys/types.h>

#include <cstddef>

namespace photomat {

// The system calls the V4L2 backend makes, behind one interface: the seam where tests put an
// emulated device (capture/testing/emulated_v4l2_device.h) under the unchanged production code.
// Every call has the libc contract: -1 (MAP_FAILED for Mmap) with errno set on failure.
class V4l2Syscalls {
 public:
  virtual ~V4l2Syscalls() = default;
  virtual int Open(const char* path, int flags) = 0;
  virtual int Close(int fd) = 0;
  virtual int Ioctl(int fd, unsigned long request, void* argument) = 0;
  virtual void* Mmap(std::size_t length, int protection, int flags, int fd, off_t offset) = 0;
  virtual int Munmap(void* address, std::size_t length) = 0;
  virtual int Poll(pollfd* fds, nfds_t count, int timeout_ms) = 0;
};

// The real kernel interface.
class LinuxV4l2Syscalls final : public V4l2Syscalls {
 public:
  int Open(const char* path, int flags) override;
  int Close(int fd) override;
  int Ioctl(int fd, unsigned long request, void* argument) override;
  void* Mmap(std::size_t length, int protection, int flags, int fd, off_t offset) override;
  int Munmap(void* address, std::size_t length) override;
  int Poll(pollfd* fds, nfds_t count, int timeout_ms) override;
};

}  // namespace photomat
