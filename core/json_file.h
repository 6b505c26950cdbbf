#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace photomat {

// Parses a JSON file; a syntax error is reported as an Error naming the file, line and column.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

// Writes `value` pretty-printed, atomically.
void WriteJsonFile(const std::filesystem::path& path, const nlohmann::json& value);

// Typed access to a JSON document with errors that name the file and the JSON path of the fault
// ("manifest.json: images[3].light: expected an array of 3 numbers").
class JsonReader {
 public:
  JsonReader(const nlohmann::json& value, std::filesystem::path file, std::string where = "");

  const nlohmann::json& value() const { return value_; }
  const std::string& where() const { return where_; }
  bool Has(const std::string& key) const;

  JsonReader operator[](const std::string& key) const;  // required member
  JsonReader operator[](std::size_t index) const;       // required element
  std::size_t ArraySize() const;                        // requires an array

  std::string String() const;
  double Number() const;  // finite
  int Integer() const;
  bool Boolean() const;
  std::vector<double> Numbers() const;  // array of finite numbers

  [[noreturn]] void Fail(const std::string& fault) const;

 private:
  const nlohmann::json& value_;
  std::filesystem::path file_;
  std::string where_;
};

// A matrix as an array of its rows (arrays of numbers), and back; reading throws Error (through
// `json`) for an empty matrix or a row of another length than `columns`.
nlohmann::json MatrixToJson(const Eigen::MatrixXd& matrix);
Eigen::MatrixXd MatrixFromJson(const JsonReader& json, Eigen::Index columns);

}  // namespace photomat
