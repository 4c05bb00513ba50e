#pragma once
// The one CSV writer of the benchmarks (their --csv files): a header row, then
// rows of fields, held in memory and written to the file at the end, so a run
// that fails never leaves a half-written table behind a finished-looking name.

#include <concepts>
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace shatter::bench {

/// `value` as the shortest decimal that reads back as exactly `value` ("0.1",
/// "65536", "1e-07"); empty for NaN and infinities, which in the benchmarks mean
/// a measurement not taken or a ratio over zero.
std::string csv_number(double value);

/// A CSV table (RFC 4180 fields, LF line ends). Text fields are quoted only when
/// they hold a comma, a double quote or a line break; doubles are written as the
/// shortest decimal that reads back as exactly the same double, so a figure in
/// the CSV is the figure measured, not a rounding of it.
///
/// Every row must have as many fields as the header has columns: end_row()
/// throws std::logic_error otherwise, so a column added to the header but not
/// to the rows (or the reverse) fails the run instead of shifting every later
/// column.
class CsvWriter {
 public:
  /// Starts the table with its header row: `header` is the column names joined
  /// by commas ("mesh,triangles,seconds"). Precondition: no name is empty or
  /// holds a quote or a line break (std::logic_error otherwise), so the header
  /// is written as given and its comma count fixes the number of columns.
  explicit CsvWriter(std::string_view header);

  /// Appends a text field, quoted if needed (inner quotes doubled).
  CsvWriter& field(std::string_view text);
  CsvWriter& field(const char* text) { return field(std::string_view(text)); }
  CsvWriter& field(const std::string& text) { return field(std::string_view(text)); }
  /// Appends a number as csv_number() writes it (NaN and infinities as an empty field).
  CsvWriter& field(double value) { return append_raw(csv_number(value)); }
  /// Appends an integer in decimal (a bool as 0 or 1).
  template <std::integral Integer>
  CsvWriter& field(Integer value) {
    return append_raw(std::to_string(value));
  }
  /// Appends `value` when `present`, else an empty field: for counts that only
  /// exist when a build or a check ran.
  template <class Value>
  CsvWriter& field_if(bool present, const Value& value) {
    return present ? field(value) : empty();
  }
  /// Appends `count` empty fields (the columns of a part that did not run).
  CsvWriter& empty(std::size_t count = 1);

  /// Ends the current row. Throws std::logic_error when it does not have one
  /// field per column.
  void end_row();

  /// The table so far (header and finished rows).
  const std::string& text() const { return text_; }

  /// Writes the table to `path`, replacing the file. Precondition: no row is
  /// left unfinished (std::logic_error otherwise). Throws std::runtime_error
  /// when the file cannot be opened or written.
  void save(const std::filesystem::path& path) const;

 private:
  CsvWriter& append_raw(std::string_view text);

  std::size_t columns_ = 0;
  std::size_t fields_in_row_ = 0;
  std::string text_;
};

}  // namespace shatter::bench
