#include "capture/live/testing/reported_exposure_source.h"

namespace photomat::testing {

Frame ReportedExposureSource::Grab(std::chrono::milliseconds timeout) {
  Frame frame = source_.Grab(timeout);
  frame.metadata.exposure_us = device_.FrameExposureUs(frame.metadata.sequence);
  return frame;
}

}  // namespace photomat::testing
