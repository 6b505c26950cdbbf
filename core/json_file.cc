#include "core/json_file.h"

#include <fmt/format.h>

#include <cmath>

#include "core/atomic_file.h"
#include "core/error.h"

namespace photomat {

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  const std::string text = ReadTextFile(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& error) {
    // Turn the byte offset into a line and column a person can find.
    const std::size_t offset = std::min(error.byte == 0 ? 0 : error.byte - 1, text.size());
    const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(offset), '\n');
    const std::size_t line_start = text.rfind('\n', offset == 0 ? 0 : offset - 1);
    const std::size_t column = offset - (line_start == std::string::npos ? 0 : line_start + 1) + 1;
    throw Error(path, fmt::format("invalid JSON at line {}, column {}", line, column));
  } catch (const nlohmann::json::exception& error) {
    // Well-formed JSON the parser still cannot hold, e.g. a number beyond double's range
    // (out_of_range 406): the fuzzer found that this escaped as a foreign exception.
    throw Error(path, fmt::format("unreadable JSON: {}", error.what()));
  }
}

void WriteJsonFile(const std::filesystem::path& path, const nlohmann::json& value) {
  WriteTextFileAtomically(path, value.dump(2) + "\n");
}

JsonReader::JsonReader(const nlohmann::json& value, std::filesystem::path file, std::string where)
    : value_(value), file_(std::move(file)), where_(std::move(where)) {}

bool JsonReader::Has(const std::string& key) const {
  return value_.is_object() && value_.contains(key) && !value_.at(key).is_null();
}

JsonReader JsonReader::operator[](const std::string& key) const {
  if (!value_.is_object()) Fail("expected an object");
  const std::string path = where_.empty() ? key : where_ + "." + key;
  if (!value_.contains(key)) {
    throw Error(file_, fmt::format("missing \"{}\"{}", key,
                                   where_.empty() ? "" : fmt::format(" in {}", where_)));
  }
  return JsonReader(value_.at(key), file_, path);
}

JsonReader JsonReader::operator[](std::size_t index) const {
  if (!value_.is_array() || index >= value_.size()) Fail("expected more array elements");
  return JsonReader(value_.at(index), file_, fmt::format("{}[{}]", where_, index));
}

std::size_t JsonReader::ArraySize() const {
  if (!value_.is_array()) Fail("expected an array");
  return value_.size();
}

std::string JsonReader::String() const {
  if (!value_.is_string()) Fail("expected a string");
  return value_.get<std::string>();
}

double JsonReader::Number() const {
  if (!value_.is_number()) Fail("expected a number");
  const double v = value_.get<double>();
  if (!std::isfinite(v)) Fail("expected a finite number");
  return v;
}

int JsonReader::Integer() const {
  if (!value_.is_number_integer()) Fail("expected an integer");
  const auto v = value_.get<long long>();
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    Fail("integer out of range");
  }
  return static_cast<int>(v);
}

bool JsonReader::Boolean() const {
  if (!value_.is_boolean()) Fail("expected true or false");
  return value_.get<bool>();
}

std::vector<double> JsonReader::Numbers() const {
  if (!value_.is_array()) Fail("expected an array of numbers");
  std::vector<double> numbers;
  for (std::size_t i = 0; i < value_.size(); ++i) numbers.push_back((*this)[i].Number());
  return numbers;
}

void JsonReader::Fail(const std::string& fault) const {
  throw Error(file_, where_.empty() ? fault : fmt::format("{}: {}", where_, fault));
}

nlohmann::json MatrixToJson(const Eigen::MatrixXd& matrix) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) row.push_back(matrix(r, c));
    rows.push_back(std::move(row));
  }
  return rows;
}

Eigen::MatrixXd MatrixFromJson(const JsonReader& json, Eigen::Index columns) {
  const std::size_t rows = json.ArraySize();
  if (rows == 0) json.Fail("empty matrix");
  Eigen::MatrixXd matrix(rows, columns);
  for (std::size_t r = 0; r < rows; ++r) {
    const std::vector<double> row = json[r].Numbers();
    if (static_cast<Eigen::Index>(row.size()) != columns) {
      json[r].Fail(fmt::format("expected {} numbers", columns));
    }
    for (Eigen::Index c = 0; c < columns; ++c) matrix(r, c) = row[c];
  }
  return matrix;
}

}  // namespace photomat
