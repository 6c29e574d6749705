// Text tables of numbers, one record per line, as TetGen's .node and .ele
// files and partition files hold them: comments ('#' to the end of a line)
// and blank lines dropped, fields split on blanks or commas, every field
// parsed whole or refused with the file and line.
#pragma once

#include <charconv>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io_formats.hpp"
#include "tetiso/error.hpp"

namespace tetiso::detail {

// The data lines of a table file: comments and blank lines dropped, each
// line split into its fields, with its line number for messages.
class TableFile {
public:
    explicit TableFile(std::filesystem::path path)
        : path_(std::move(path)), in_(detail::open_for_reading(path_)) {}

    // Reads the next data line into fields(); false at the end of the file.
    bool next() {
        std::string line;
        while (std::getline(in_, line)) {
            ++line_number_;
            if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
            split(line);
            if (!fields_.empty()) return true;
        }
        return false;
    }

    std::size_t size() const { return fields_.size(); }

    template <class T>
    T get(std::size_t i, const char* what) const {
        if (i >= fields_.size()) fail(std::string("missing ") + what);
        const std::string& text = fields_[i];
        T value{};
        const char* const last = text.data() + text.size();
        const auto [end, ec] = std::from_chars(past_plus(text.data(), last), last, value);
        if (ec != std::errc() || end != last)
            fail(std::string(what) + " '" + text + "' is not a number of the expected kind");
        return value;
    }

    [[noreturn]] void fail(const std::string& what) const {
        throw Error(path_.string() + ":" + std::to_string(line_number_) + ": " + what);
    }
    [[noreturn]] void fail_file(const std::string& what) const { throw Error(path_.string() + ": " + what); }

private:
    void split(const std::string& line) {
        fields_.clear();
        std::size_t i = 0;
        while (i < line.size()) {
            while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r' || line[i] == ',')) ++i;
            const std::size_t start = i;
            while (i < line.size() && !(line[i] == ' ' || line[i] == '\t' || line[i] == '\r' || line[i] == ',')) ++i;
            if (i > start) fields_.emplace_back(line, start, i - start);
        }
    }

    std::filesystem::path path_;
    std::ifstream in_;
    std::vector<std::string> fields_;
    std::size_t line_number_ = 0;
};

} // namespace tetiso::detail
