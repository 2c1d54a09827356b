// The --json summaries' one writer: an object written field by field, with the commas and the
// nesting kept track of. Integers are written as they are, doubles as a stream prints them (six
// significant digits: measures and times) or, with exact(), shortest round-trip (coordinates).
#pragma once

#include "core/exact/predicates.hpp"
#include "io/common/json_text.hpp"

#include <concepts>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace toposimp::cli {

class JsonWriter {
public:
    JsonWriter() { open('{', '}'); }

    template <class T>
    JsonWriter& field(std::string_view key, const T& value) {
        name(key);
        write(value);
        return *this;
    }
    // A double written shortest round-trip.
    JsonWriter& exact(std::string_view key, double value) {
        name(key);
        out_ << io::json_number(value);
        return *this;
    }
    // Opens an object or an array as the value of `key`; end() closes it.
    JsonWriter& object(std::string_view key) {
        name(key);
        open('{', '}');
        return *this;
    }
    JsonWriter& array(std::string_view key) {
        name(key);
        open('[', ']');
        return *this;
    }
    // An object or a value as the next item of the innermost array.
    JsonWriter& object() {
        separate();
        open('{', '}');
        return *this;
    }
    template <class T>
    JsonWriter& item(const T& value) {
        separate();
        write(value);
        return *this;
    }
    JsonWriter& end() {
        out_ << closing_.back();
        closing_.pop_back();
        first_.pop_back();
        return *this;
    }
    // Everything closed, and a newline: one line of JSON.
    std::string line() {
        while (!closing_.empty()) end();
        return out_.str() + "\n";
    }

private:
    void open(char opening, char closing) {
        out_ << opening;
        closing_.push_back(closing);
        first_.push_back(true);
    }
    void separate() {
        if (!first_.back()) out_ << ',';
        first_.back() = false;
    }
    void name(std::string_view key) {
        separate();
        out_ << io::json_string(std::string(key)) << ':';
    }
    void write(bool value) { out_ << (value ? "true" : "false"); }
    void write(const std::string& value) { out_ << io::json_string(value); }
    void write(const char* value) { out_ << io::json_string(value); }
    template <class T>
        requires std::integral<T> || std::floating_point<T>
    void write(T value) {
        out_ << value;
    }

    std::ostringstream out_;
    std::vector<char> closing_;
    std::vector<bool> first_;
};

// How the exact predicates were decided, as both engines' summaries report it.
inline void add_predicates(JsonWriter& json, const exact::PredicateStats& predicates) {
    json.object("predicates")
        .field("filter_decided", predicates.filter_decided)
        .field("expansion_decided", predicates.expansion_decided)
        .field("gmp_fallbacks", predicates.gmp_fallbacks)
        .end();
}

}  // namespace toposimp::cli
