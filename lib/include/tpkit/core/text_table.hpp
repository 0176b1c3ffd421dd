// The tpkit text file: the generic layer below every file kind (formats.hpp).
//
//   # tpkit KIND VERSION            first line: names the kind and its version
//   # written-by: TOOL VERSION      the tool and tpkit version that wrote it (not kept as metadata)
//   # image1: PATH WIDTH HEIGHT     images involved, numbered from 1
//   # key: value                    any other metadata (kept in order, written back)
//   # columns: name name ...        names every column of the records
//   1.5 2.25 ...                    one record per line, whitespace separated
//
// '#' lines may stand anywhere; blank lines are ignored. Pixel coordinates: x = column, y = row,
// origin at the centre of the top-left pixel. Numbers are written in the shortest form that reads back
// to the same double. A reader finds columns by name; input without a header gets the kind's default
// columns, so that the output of awk can be piped in. Bad records raise InputError("file:line: reason").
#pragma once
#include <functional>
#include <istream>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace tpkit {

struct ImageRef {
  std::string path;
  long width = 0;
  long height = 0;
};

// Ordered "# key: value" metadata lines.
using Meta = std::vector<std::pair<std::string, std::string>>;
// Value of the first metadata line with that key, or "" when absent.
std::string meta_get(const Meta& meta, const std::string& key);
// Replaces the first line with that key, or appends one.
void meta_set(Meta& meta, const std::string& key, const std::string& value);

struct TextTable {
  std::string source;      // file name for messages ("-" is shown as "<stdin>")
  std::string kind;        // from the first line; "" if the input had no header
  int version = 0;         // 0 if the input had no header
  std::string written_by;  // "# written-by:" value, "" if absent
  std::vector<ImageRef> images;
  Meta meta;
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  std::vector<long> row_line;  // line number of each record in the source
  // Raw records for kinds whose records are not one flat table (trifocal, cameras): each comment
  // line that came between records, keyed by the index of the next record.
  std::vector<std::pair<size_t, std::string>> interleaved_comments;

  // Index of a column, or -1.
  int find(const std::string& name) const;
  // Index of a column; throws InputError naming the file when the column is missing.
  int require(const std::string& name) const;
  // One column as a vector.
  std::vector<double> column(const std::string& name) const;
};

struct ReadOptions {
  // Expected kind ("matches", "tracks", ...). A header naming another kind is an error.
  std::string kind;
  int max_version = 1;
  // Default columns for headerless input, given the number of fields of the first record.
  // Return an empty vector to reject that field count.
  std::function<std::vector<std::string>(size_t nfields)> default_columns;
  // When false, records may have any number of fields (matrix kinds); columns are not checked.
  bool columnar = true;
  // Columns whose field may be "nan" (a value that is not there, e.g. a view a track is not seen in); in
  // every other column, and for infinities everywhere, a non-finite field is an error. Empty: none. Rows of
  // any length (columnar false): asked with "" for a field beyond the named columns.
  std::function<bool(const std::string& column)> may_be_missing;
  // With no kind expected: the options of the kind the header names, taken on when the header is read (a
  // reader of any kind reads a tracks file by the tracks options: version 2, views not seen). Unset: these
  // options for every kind.
  std::function<ReadOptions(const std::string& kind)> of_kind;
};

// Parses a whole stream. `source` names it in messages.
TextTable read_table(std::istream& in, const std::string& source, const ReadOptions& opt);
// Opens a path ("-" = stdin) and parses it.
TextTable read_table_file(const std::string& path, const ReadOptions& opt);

// Shortest decimal form that reads back to exactly the same double.
std::string format_number(double v);
// A figure for a message: `digits` significant digits ("%.*g"), e.g. 21.06 for a median of 21.059228...
std::string format_figure(double v, int digits = 4);
// Integer-valued doubles (ids) are written without a decimal point.
std::string format_id(double v);

// Header lines: "# tpkit KIND VERSION", "# written-by: TOOL VERSION" (tool_name(), version_full()), image lines, metadata lines, and (if non-empty) columns.
void write_header(std::ostream& os, const std::string& kind, int version, const std::vector<ImageRef>& images,
                  const Meta& meta, const std::vector<std::string>& columns);
// Writes one record, each value by format_number().
void write_record(std::ostream& os, const std::vector<double>& values);

}  // namespace tpkit
