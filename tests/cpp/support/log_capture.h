// Test helper: collects SHGI's warnings (and errors) while it lives, restoring the sink after.
#pragma once

#include <string>

#include "util/log.h"

namespace shgi::testing {

class LogCapture {
  public:
    LogCapture() {
        previous_ = set_log_sink([this](LogLevel level, const std::string& message) {
            if (level >= LogLevel::Warning) warnings += message + "\n";
        });
    }
    ~LogCapture() { set_log_sink(previous_); }
    LogCapture(const LogCapture&) = delete;
    LogCapture& operator=(const LogCapture&) = delete;

    std::string warnings;

  private:
    LogSink previous_;
};

}  // namespace shgi::testing
