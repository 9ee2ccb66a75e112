// Log sink: where SHGI's warnings and information go.
//
// The default sink writes to stderr. The Python bindings replace it (shgi.set_log_sink) so that
// warnings reach Python's logging module or Blender's report system. The sink may be called
// from worker threads; calls are serialised by a mutex, so a sink need not be thread-safe. No
// other lock is held while it runs: it may replace the sink (the running call finishes with the
// one it started with), and what it logs itself goes to stderr instead of re-entering it.
#pragma once

#include <functional>
#include <string>

#include "util/error.h"

namespace shgi {

enum class LogLevel { Debug = 0, Info = 1, Warning = 2, Error = 3 };

using LogSink = std::function<void(LogLevel, const std::string&)>;

// Replaces the sink; an empty function restores the default (stderr). Returns the previous one.
LogSink set_log_sink(LogSink sink);

// Messages below this level are dropped before reaching the sink (default: Info).
void set_log_level(LogLevel level);
LogLevel log_level();

void log_message(LogLevel level, const std::string& message);

template <typename... Parts>
void log_info(Parts&&... parts) {
    if (log_level() <= LogLevel::Info)
        log_message(LogLevel::Info, format_message(std::forward<Parts>(parts)...));
}

template <typename... Parts>
void log_warning(Parts&&... parts) {
    if (log_level() <= LogLevel::Warning)
        log_message(LogLevel::Warning, format_message(std::forward<Parts>(parts)...));
}

const char* log_level_name(LogLevel level);

}  // namespace shgi
