#include "csv.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <stdexcept>

namespace shatter::bench {

std::string csv_number(double value) {
  if (!std::isfinite(value)) return "";
  char buffer[32];  // the longest shortest double, "-2.2250738585072014e-308", is 24 characters
  return std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, value).ptr);
}

CsvWriter::CsvWriter(std::string_view header) {
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = header.find(',', start);
    const std::string_view name = header.substr(start, comma == std::string_view::npos ? comma : comma - start);
    if (name.empty() || name.find_first_of("\"\r\n") != std::string_view::npos)
      throw std::logic_error("bad CSV column name '" + std::string(name) + "' in the header");
    append_raw(name);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  columns_ = fields_in_row_;
  end_row();
}

CsvWriter& CsvWriter::append_raw(std::string_view text) {
  if (fields_in_row_++ > 0) text_ += ',';
  text_ += text;
  return *this;
}

CsvWriter& CsvWriter::field(std::string_view text) {
  if (text.find_first_of(",\"\r\n") == std::string_view::npos) return append_raw(text);
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  quoted += '"';
  return append_raw(quoted);
}

CsvWriter& CsvWriter::empty(std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) append_raw("");
  return *this;
}

void CsvWriter::end_row() {
  if (fields_in_row_ != columns_) {
    throw std::logic_error("a CSV row has " + std::to_string(fields_in_row_) + " fields, the header " +
                           std::to_string(columns_) + " columns");
  }
  text_ += '\n';
  fields_in_row_ = 0;
}

void CsvWriter::save(const std::filesystem::path& path) const {
  if (fields_in_row_ != 0) throw std::logic_error("a CSV row was left unfinished");
  std::ofstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error("cannot open " + path.string() + " for writing");
  file << text_;
  if (!file.flush()) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace shatter::bench
