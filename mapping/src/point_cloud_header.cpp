// PLY and PCD header checks against the file's body (see point_cloud_header.hpp).
#include "rowloc/mapping/point_cloud_header.hpp"

#include <array>
#include <charconv>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::mapping {
namespace {

using Path = std::filesystem::path;

/// Reads header lines with bounded length and total size; tracks the line number and offset.
class HeaderLines {
 public:
  HeaderLines(std::istream& in, const Path& name) : in_(in), name_(name) {}

  /// The next line without its "\n" (and "\r"); nullopt at the end of the file.
  std::optional<std::string> Next() {
    std::string line;
    char c = 0;
    bool any = false;
    while (in_.get(c)) {
      any = true;
      ++offset_;
      if (offset_ > kMaxHeaderBytes) Fail("the header is longer than " + std::to_string(kMaxHeaderBytes) + " bytes");
      if (c == '\n') break;
      if (line.size() >= kMaxHeaderLineBytes) {
        Fail("header line " + std::to_string(line_ + 1) + " is longer than " + std::to_string(kMaxHeaderLineBytes) +
             " bytes");
      }
      line.push_back(c);
    }
    if (!any) return std::nullopt;
    ++line_;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return line;
  }

  [[noreturn]] void Fail(const std::string& reason) const { throw PointCloudError(name_, reason); }
  [[noreturn]] void FailHere(const std::string& reason) const {
    throw PointCloudError(name_, "line " + std::to_string(line_) + ": " + reason);
  }
  std::size_t line() const { return line_; }
  std::uint64_t offset() const { return offset_; }

 private:
  std::istream& in_;
  const Path& name_;
  std::size_t line_ = 0;
  std::uint64_t offset_ = 0;
};

std::vector<std::string_view> Words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

std::optional<std::uint64_t> ParseCount(std::string_view word) {
  std::uint64_t value = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
  if (ec != std::errc() || end != word.data() + word.size()) return std::nullopt;
  return value;
}

std::uint64_t RequireCount(const HeaderLines& lines, std::string_view key, std::string_view word,
                           std::uint64_t max = std::numeric_limits<std::uint32_t>::max()) {
  const std::optional<std::uint64_t> value = ParseCount(word);
  if (!value || *value > max) {
    lines.FailHere(std::string(key) + ": '" + std::string(word) + "' is not a whole number in [0, " +
                   std::to_string(max) + "]");
  }
  return *value;
}

/// Bytes from the stream's position to its end; the position is kept.
std::uint64_t RemainingBytes(std::istream& in) {
  in.clear();
  const std::istream::pos_type here = in.tellg();
  in.seekg(0, std::ios::end);
  const std::istream::pos_type end = in.tellg();
  in.seekg(here);
  return here < 0 || end < here ? 0 : static_cast<std::uint64_t>(end - here);
}

/// Checks `needed` (a product of header claims, computed without overflow) against the body.
void RequireBodyBytes(const HeaderLines& lines, std::uint64_t body, long double needed, bool exact,
                      const std::string& claim) {
  if (static_cast<long double>(body) < needed) {
    lines.Fail(claim + " needs " + std::to_string(static_cast<unsigned long long>(needed)) + " bytes of data, but only " +
               std::to_string(body) + " follow the header (truncated file, or a header that claims too much)");
  }
  if (exact && static_cast<long double>(body) > needed) {
    lines.Fail(claim + " needs " + std::to_string(static_cast<unsigned long long>(needed)) + " bytes of data, but " +
               std::to_string(body) + " follow the header (the header does not describe the data)");
  }
}

/// Scans an ASCII body line by line in blocks: for each line with values, `check(line_number,
/// record_index, values)`; returns the number of such lines. A line of white space only (spaces,
/// tabs, "\r") is a record of 0 values when `blank_is_record` (PCL's PCD reader skips only empty
/// lines: it reads "  " or "\r" as a point of zeros), else skipped like an empty line. A line
/// longer than kMaxAsciiLineBytes is refused when that many bytes of it have been scanned (PCL
/// would read it whole: a 1 GiB line of spaces took 2.2 GB).
template <typename Check>
std::uint64_t ScanAsciiLines(std::istream& in, std::size_t first_line, const Path& name, bool blank_is_record,
                             const Check& check) {
  std::array<char, 1 << 16> buffer{};
  std::size_t line = first_line;
  std::uint64_t records = 0, values = 0, bytes = 0;
  bool in_word = false;
  const auto end_line = [&] {
    if (values > 0 || (blank_is_record && bytes > 0)) check(line, records++, values);
    values = 0;
    bytes = 0;
    in_word = false;
    ++line;
  };
  while (in.read(buffer.data(), buffer.size()) || in.gcount() > 0) {
    const std::streamsize n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i) {
      const char c = buffer[static_cast<std::size_t>(i)];
      if (c == '\n') {
        end_line();
        continue;
      }
      if (++bytes > kMaxAsciiLineBytes) {
        throw PointCloudError(name, "line " + std::to_string(line) + " is longer than " +
                                        std::to_string(kMaxAsciiLineBytes) + " bytes");
      }
      if (c == ' ' || c == '\t' || c == '\r') {
        in_word = false;
      } else if (!in_word) {
        in_word = true;
        ++values;
      }
    }
  }
  if (values > 0 || (blank_is_record && bytes > 0)) end_line();
  return records;
}

// ---------------------------------------------------------------------------------------------
// PCD

struct PcdHeader {
  std::vector<std::string> fields;
  std::vector<std::uint64_t> sizes, counts;
  std::optional<std::uint64_t> width, height, points;
  PointCloudEncoding encoding = PointCloudEncoding::kAscii;
  bool has_type = false, has_data = false;
};

void ParsePcdLine(HeaderLines& lines, const std::vector<std::string_view>& w, PcdHeader& h) {
  const std::string_view key = w[0];
  const std::size_t n = w.size() - 1;
  if (key == "FIELDS") {
    if (n == 0 || n > kMaxFields) lines.FailHere("FIELDS: expected 1 to " + std::to_string(kMaxFields) + " fields, got " + std::to_string(n));
    for (std::size_t i = 1; i < w.size(); ++i) h.fields.emplace_back(w[i]);
  } else if (key == "SIZE") {
    for (std::size_t i = 1; i < w.size(); ++i) {
      const std::uint64_t s = RequireCount(lines, "SIZE", w[i], 8);
      if (s != 1 && s != 2 && s != 4 && s != 8) lines.FailHere("SIZE: " + std::to_string(s) + " is not 1, 2, 4 or 8 bytes");
      h.sizes.push_back(s);
    }
  } else if (key == "TYPE") {
    for (std::size_t i = 1; i < w.size(); ++i) {
      if (w[i] != "I" && w[i] != "U" && w[i] != "F") lines.FailHere("TYPE: '" + std::string(w[i]) + "' is not I, U or F");
    }
    h.has_type = true;
  } else if (key == "COUNT") {
    for (std::size_t i = 1; i < w.size(); ++i) {
      const std::uint64_t c = RequireCount(lines, "COUNT", w[i], kMaxValuesPerPoint);
      if (c == 0) lines.FailHere("COUNT: 0 values for field " + std::to_string(i));
      h.counts.push_back(c);
    }
  } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
    if (n != 1) lines.FailHere(std::string(key) + ": expected one number");
    const std::uint64_t value = RequireCount(lines, key, w[1]);
    (key == "WIDTH" ? h.width : key == "HEIGHT" ? h.height : h.points) = value;
  } else if (key == "DATA") {
    if (n != 1) lines.FailHere("DATA: expected ascii, binary or binary_compressed");
    if (w[1] == "ascii") h.encoding = PointCloudEncoding::kAscii;
    else if (w[1] == "binary") h.encoding = PointCloudEncoding::kBinary;
    else if (w[1] == "binary_compressed") h.encoding = PointCloudEncoding::kBinaryCompressed;
    else lines.FailHere("DATA: '" + std::string(w[1]) + "' is not ascii, binary or binary_compressed");
    h.has_data = true;
  } else if (key.find_first_not_of("0123456789+-.eE") == std::string_view::npos) {
    lines.FailHere("a number where a header key is expected: the PCD header has no DATA line before its points");
  } else if (key != "VERSION" && key != "VIEWPOINT") {
    lines.FailHere("unknown PCD header key '" + std::string(key) + "'");
  }
}

/// Consistency of the parsed header; returns the values per point.
std::uint64_t CheckPcdHeader(HeaderLines& lines, PcdHeader& h) {
  if (!h.has_data) lines.Fail("the PCD header has no DATA line");
  if (h.fields.empty()) lines.Fail("the PCD header has no FIELDS line");
  if (h.sizes.size() != h.fields.size()) {
    lines.Fail("SIZE gives " + std::to_string(h.sizes.size()) + " sizes for " + std::to_string(h.fields.size()) + " FIELDS");
  }
  if (h.counts.empty()) h.counts.assign(h.fields.size(), 1);
  if (h.counts.size() != h.fields.size()) {
    lines.Fail("COUNT gives " + std::to_string(h.counts.size()) + " counts for " + std::to_string(h.fields.size()) + " FIELDS");
  }
  if (!h.has_type) lines.Fail("the PCD header has no TYPE line");
  std::uint64_t values = 0;
  for (const std::uint64_t c : h.counts) values += c;
  if (values > kMaxValuesPerPoint) {
    lines.Fail("COUNT adds up to " + std::to_string(values) + " values per point (at most " +
               std::to_string(kMaxValuesPerPoint) + ")");
  }
  if (!h.width || !h.height) lines.Fail("the PCD header needs WIDTH and HEIGHT");
  const std::uint64_t product = *h.width * *h.height;  // both < 2^32: no overflow
  if (!h.points) h.points = product;
  if (*h.points != product) {
    lines.Fail("POINTS " + std::to_string(*h.points) + " is not WIDTH x HEIGHT = " + std::to_string(product));
  }
  return values;
}

void CheckCompressedPcd(std::istream& in, const HeaderLines& lines, std::uint64_t body, long double needed) {
  std::array<unsigned char, 8> sizes{};
  if (body < sizes.size() || !in.read(reinterpret_cast<char*>(sizes.data()), sizes.size())) {
    lines.Fail("binary_compressed: the 8 bytes of compressed and uncompressed size are missing");
  }
  const auto le32 = [&](std::size_t at) {
    return std::uint64_t{sizes[at]} | std::uint64_t{sizes[at + 1]} << 8 | std::uint64_t{sizes[at + 2]} << 16 |
           std::uint64_t{sizes[at + 3]} << 24;
  };
  const std::uint64_t compressed = le32(0), uncompressed = le32(4);
  if (compressed > body - 8) {
    lines.Fail("binary_compressed: the block claims " + std::to_string(compressed) + " compressed bytes, but " +
               std::to_string(body - 8) + " follow");
  }
  if (static_cast<long double>(uncompressed) != needed) {
    lines.Fail("binary_compressed: the block claims " + std::to_string(uncompressed) +
               " uncompressed bytes, but POINTS x point size is " + std::to_string(static_cast<unsigned long long>(needed)));
  }
  if (uncompressed > kMaxLzfExpansion * compressed) {
    lines.Fail("binary_compressed: " + std::to_string(compressed) + " compressed bytes cannot hold " +
               std::to_string(uncompressed) + " (LZF expands at most " + std::to_string(kMaxLzfExpansion) + " times)");
  }
}

// ---------------------------------------------------------------------------------------------
// PLY

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t scalar_bytes = 0;  ///< scalars plus the count of each list
  std::size_t scalars = 0, lists = 0;
};

std::optional<std::uint64_t> PlyTypeBytes(std::string_view type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" || type == "float32") {
    return 4;
  }
  if (type == "double" || type == "float64") return 8;
  return std::nullopt;
}

std::uint64_t RequirePlyType(const HeaderLines& lines, std::string_view type) {
  const std::optional<std::uint64_t> bytes = PlyTypeBytes(type);
  if (!bytes) lines.FailHere("unknown PLY property type '" + std::string(type) + "'");
  return *bytes;
}

void ParsePlyProperty(HeaderLines& lines, const std::vector<std::string_view>& w, std::vector<PlyElement>& elements) {
  if (elements.empty()) lines.FailHere("a property before any element");
  PlyElement& e = elements.back();
  if (e.scalars + e.lists >= kMaxFields) lines.FailHere("more than " + std::to_string(kMaxFields) + " properties in element '" + e.name + "'");
  if (w.size() == 5 && w[1] == "list") {
    RequirePlyType(lines, w[3]);
    e.scalar_bytes += RequirePlyType(lines, w[2]);
    ++e.lists;
  } else if (w.size() == 3) {
    e.scalar_bytes += RequirePlyType(lines, w[1]);
    ++e.scalars;
  } else {
    lines.FailHere("expected 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME'");
  }
}

}  // namespace

PointCloudFileSummary CheckPcdFile(std::istream& in, const Path& name) {
  HeaderLines lines(in, name);
  PcdHeader h;
  while (!h.has_data) {
    const std::optional<std::string> line = lines.Next();
    if (!line) break;
    const std::vector<std::string_view> w = Words(*line);
    if (w.empty() || w[0].front() == '#') continue;
    ParsePcdLine(lines, w, h);
  }
  const std::uint64_t values = CheckPcdHeader(lines, h);
  PointCloudFileSummary s;
  s.encoding = h.encoding;
  s.points = *h.points;
  s.header_bytes = lines.offset();
  for (std::size_t i = 0; i < h.fields.size(); ++i) s.point_bytes += h.sizes[i] * h.counts[i];
  const long double needed = static_cast<long double>(s.points) * static_cast<long double>(s.point_bytes);
  const std::string claim = "POINTS " + std::to_string(s.points) + " x " + std::to_string(s.point_bytes) + " bytes";
  if (h.encoding == PointCloudEncoding::kBinary) {
    // Not exact: PCL's PCDWriter pads binary files (to a page), so more bytes may follow.
    RequireBodyBytes(lines, RemainingBytes(in), needed, /*exact=*/false, claim);
  } else if (h.encoding == PointCloudEncoding::kBinaryCompressed) {
    CheckCompressedPcd(in, lines, RemainingBytes(in), needed);
  } else {
    const std::uint64_t records = ScanAsciiLines(in, lines.line() + 1, name, /*blank_is_record=*/true,
                                                 [&](std::size_t line, std::uint64_t record, std::uint64_t n) {
      if (n == 0) {
        throw PointCloudError(name, "line " + std::to_string(line) +
                                        ": white space only (PCL would read it as a point of zeros; remove the line)");
      }
      if (record >= s.points) {
        throw PointCloudError(name, "line " + std::to_string(line) + ": more points than POINTS " + std::to_string(s.points));
      }
      if (n != values) {
        throw PointCloudError(name, "line " + std::to_string(line) + ": " + std::to_string(n) +
                                        " values, but FIELDS and COUNT announce " + std::to_string(values) + " per point");
      }
    });
    if (records < s.points) {
      lines.Fail("POINTS " + std::to_string(s.points) + " but the file holds " + std::to_string(records) +
                 " point lines (truncated file, or a header that claims too much)");
    }
  }
  return s;
}

PointCloudFileSummary CheckPlyFile(std::istream& in, const Path& name) {
  HeaderLines lines(in, name);
  const std::optional<std::string> magic = lines.Next();
  if (!magic || *magic != "ply") lines.Fail("not a PLY file (the first line is not 'ply')");
  std::optional<PointCloudEncoding> encoding;
  std::vector<PlyElement> elements;
  bool ended = false;
  while (!ended) {
    const std::optional<std::string> line = lines.Next();
    if (!line) lines.Fail("the PLY header has no end_header line");
    const std::vector<std::string_view> w = Words(*line);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "format") {
      if (w.size() != 3 || (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian")) {
        lines.FailHere("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      }
      encoding = w[1] == "ascii" ? PointCloudEncoding::kAscii : PointCloudEncoding::kBinary;
    } else if (w[0] == "element") {
      if (w.size() != 3) lines.FailHere("expected 'element NAME COUNT'");
      if (elements.size() >= kMaxFields) lines.FailHere("more than " + std::to_string(kMaxFields) + " elements");
      elements.push_back({std::string(w[1]), RequireCount(lines, "element " + std::string(w[1]), w[2]), 0, 0, 0});
    } else if (w[0] == "property") {
      ParsePlyProperty(lines, w, elements);
    } else if (w[0] == "end_header") {
      ended = true;
    } else {
      lines.FailHere("unknown PLY header keyword '" + std::string(w[0]) + "'");
    }
  }
  if (!encoding) lines.Fail("the PLY header has no format line");
  PointCloudFileSummary s;
  s.encoding = *encoding;
  s.header_bytes = lines.offset();
  long double needed = 0;
  bool lists = false;
  for (const PlyElement& e : elements) {
    if (e.count > 0 && e.scalars + e.lists == 0) lines.Fail("element '" + e.name + "' has records but no properties");
    if (e.name == "vertex") s.points = e.count, s.point_bytes = e.scalar_bytes;
    needed += static_cast<long double>(e.count) * static_cast<long double>(e.scalar_bytes);
    lists = lists || (e.count > 0 && e.lists > 0);
  }
  if (s.encoding == PointCloudEncoding::kBinary) {
    RequireBodyBytes(lines, RemainingBytes(in), needed, /*exact=*/!lists, "the elements of the header");
    return s;
  }
  std::uint64_t total = 0;
  for (const PlyElement& e : elements) total += e.count;  // each < 2^32, at most kMaxFields of them
  const std::uint64_t records = ScanAsciiLines(in, lines.line() + 1, name, /*blank_is_record=*/false,
                                               [&](std::size_t line, std::uint64_t record, std::uint64_t n) {
    if (record >= total) {
      throw PointCloudError(name, "line " + std::to_string(line) + ": more records than the header's elements (" +
                                      std::to_string(total) + ")");
    }
    std::uint64_t first = 0;
    std::size_t i = 0;
    while (record >= first + elements[i].count) first += elements[i++].count;
    const PlyElement& e = elements[i];
    const bool ok = e.lists == 0 ? n == e.scalars : n >= e.scalars + e.lists;
    if (!ok) {
      throw PointCloudError(name, "line " + std::to_string(line) + ": " + std::to_string(n) + " values, but element '" +
                                      e.name + "' has " + std::to_string(e.scalars + e.lists) + " properties");
    }
  });
  if (records < total) {
    lines.Fail("the header's elements announce " + std::to_string(total) + " records but the file holds " +
               std::to_string(records) + " lines (truncated file, or a header that claims too much)");
  }
  return s;
}

}  // namespace rowloc::mapping
