#include "util/log.h"

#include <atomic>
#include <iostream>
#include <memory>
#include <mutex>
#include <utility>

namespace shgi {
namespace {

// The sink is shared so that a call in progress keeps the one it started with while another
// thread, or the sink itself, replaces it: set_log_sink only waits for the pointer's swap.
std::mutex& sink_mutex() {  // guards current_sink()
    static std::mutex mutex;
    return mutex;
}

std::shared_ptr<const LogSink>& current_sink() {
    static std::shared_ptr<const LogSink> sink;
    return sink;
}

std::mutex& call_mutex() {  // serialises the sink's calls
    static std::mutex mutex;
    return mutex;
}

// The thread is inside the sink: what it logs there goes to stderr (the sink is not re-entered,
// and call_mutex() is not taken twice).
thread_local bool t_in_sink = false;

void write_to_stderr(LogLevel level, const std::string& message) {
    std::cerr << "shgi " << log_level_name(level) << ": " << message << '\n';
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
    auto next = sink ? std::make_shared<const LogSink>(std::move(sink)) : nullptr;
    std::shared_ptr<const LogSink> previous;
    {
        std::lock_guard<std::mutex> lock(sink_mutex());
        previous = std::exchange(current_sink(), std::move(next));
    }
    // A call that is running keeps its own reference; the caller gets a copy of the function.
    return previous ? *previous : LogSink();
}

void set_log_level(LogLevel level) { g_level.store(static_cast<int>(level)); }

LogLevel log_level() { return static_cast<LogLevel>(g_level.load()); }

void log_message(LogLevel level, const std::string& message) {
    if (level < log_level()) return;
    std::shared_ptr<const LogSink> sink;
    {
        std::lock_guard<std::mutex> lock(sink_mutex());
        sink = current_sink();
    }
    if (t_in_sink) return write_to_stderr(level, message);
    std::lock_guard<std::mutex> lock(call_mutex());
    if (!sink) return write_to_stderr(level, message);
    t_in_sink = true;
    // A sink that throws must not unwind into a worker thread of TBB.
    try {
        (*sink)(level, message);
    } catch (...) {
        std::cerr << "shgi: log sink threw; message was: " << message << '\n';
    }
    t_in_sink = false;
}

}  // namespace shgi
