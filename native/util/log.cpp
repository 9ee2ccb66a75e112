#include "util/log.h"

#include <atomic>
#include <iostream>
#include <mutex>

namespace shgi {
namespace {

std::mutex& sink_mutex() {
    static std::mutex mutex;
    return mutex;
}

LogSink& current_sink() {
    static LogSink sink;
    return sink;
}

std::atomic<int> g_level{static_cast<int>(LogLevel::Info)};

}  // namespace

const char* log_level_name(LogLevel level) {
    switch (level) {
        case LogLevel::Debug: return "debug";
        case LogLevel::Info: return "info";
        case LogLevel::Warning: return "warning";
        case LogLevel::Error: return "error";
    }
    return "unknown";
}

LogSink set_log_sink(LogSink sink) {
    std::lock_guard<std::mutex> lock(sink_mutex());
    LogSink previous = std::move(current_sink());
    current_sink() = std::move(sink);
    return previous;
}

void set_log_level(LogLevel level) { g_level.store(static_cast<int>(level)); }

LogLevel log_level() { return static_cast<LogLevel>(g_level.load()); }

void log_message(LogLevel level, const std::string& message) {
    if (level < log_level()) return;
    std::lock_guard<std::mutex> lock(sink_mutex());
    if (current_sink()) {
        // A sink that throws must not unwind into a worker thread of TBB.
        try {
            current_sink()(level, message);
        } catch (...) {
            std::cerr << "shgi: log sink threw; message was: " << message << '\n';
        }
        return;
    }
    std::cerr << "shgi " << log_level_name(level) << ": " << message << '\n';
}

}  // namespace shgi
