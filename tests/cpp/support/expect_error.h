// Test helpers for "this input is rejected with a message that names it" (STYLE.md, habit 6):
// expect_error<E> fails when the action throws nothing and, when it throws E, checks that the
// message contains every expected part; any other exception escapes and fails the test.
// rejection<E> returns the message instead ("" when nothing was thrown), for tests that compare
// several messages or expect none.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "util/error.h"

namespace shgi::testing {

// Runs `action`, expects an exception of type E whose message contains every part.
template <typename E, typename Action>
void expect_error(Action action, const std::vector<std::string>& parts) {
    try {
        action();
        ADD_FAILURE() << "expected an exception mentioning " << parts.front();
    } catch (const E& error) {
        for (const std::string& part : parts) {
            EXPECT_NE(std::string(error.what()).find(part), std::string::npos)
                << "message \"" << error.what() << "\" does not mention \"" << part << "\"";
        }
    }
}

// Expects `call` to throw InvalidArgument whose message mentions `name`.
inline void expect_invalid_argument(const std::function<void()>& call, const std::string& name) {
    expect_error<InvalidArgument>(call, {name});
}

// Runs `action` and returns the message of the E it throws, "" when it throws nothing.
template <typename E = InvalidArgument>
std::string rejection(const std::function<void()>& action) {
    try {
        action();
    } catch (const E& error) {
        return error.what();
    }
    return "";
}

inline void expect_contains(const std::string& message, const std::string& part) {
    EXPECT_NE(message.find(part), std::string::npos) << "message: '" << message << "'";
}

}  // namespace shgi::testing
