#include "server/gateway/request_fields.h"

#include <google/protobuf/descriptor.h>

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "absl/numeric/int128.h"
#include "absl/status/statusor.h"
#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"

namespace fremen::server {

namespace {

using google::protobuf::EnumValueDescriptor;
using google::protobuf::FieldDescriptor;
using google::protobuf::Message;
using google::protobuf::Reflection;

absl::Status Bad(absl::string_view dotted, absl::string_view what, absl::string_view value) {
  return absl::InvalidArgumentError(absl::StrCat("query parameter ", dotted, ": ", what, ": ", value));
}

template <typename T>
absl::Status ParseInteger(absl::string_view dotted, absl::string_view value, const FieldDescriptor& field, T& out) {
  if (absl::SimpleAtoi(value, &out)) return absl::OkStatus();
  absl::int128 wide = 0;
  if (!absl::SimpleAtoi(value, &wide)) return Bad(dotted, "not an integer", value);
  return Bad(dotted, absl::StrCat("out of range for ", field.type_name()), value);
}

absl::Status ParseDouble(absl::string_view dotted, absl::string_view value, double& out) {
  if (!absl::SimpleAtod(value, &out) || !std::isfinite(out)) return Bad(dotted, "not a finite number", value);
  return absl::OkStatus();
}

absl::StatusOr<const EnumValueDescriptor*> ParseEnum(absl::string_view dotted, absl::string_view value,
                                                     const FieldDescriptor& field) {
  const auto* type = field.enum_type();
  if (const EnumValueDescriptor* named = type->FindValueByName(std::string(value)); named != nullptr) return named;
  int number = 0;
  if (absl::SimpleAtoi(value, &number)) {
    if (const EnumValueDescriptor* numbered = type->FindValueByNumber(number); numbered != nullptr) return numbered;
  }
  return Bad(dotted, absl::StrCat("not a value of ", type->full_name()), value);
}

// Reflection's setter (or adder) of a field of type T.
template <typename T>
using Setter = void (Reflection::*)(Message*, const FieldDescriptor*, T) const;

// Sets `v`, or appends it to a repeated field.
template <typename T>
absl::Status Store(const FieldDescriptor& field, Message& message, T v, Setter<T> set, Setter<T> add) {
  (message.GetReflection()->*(field.is_repeated() ? add : set))(&message, &field, std::move(v));
  return absl::OkStatus();
}

template <typename T>
absl::Status StoreInteger(absl::string_view dotted, absl::string_view value, const FieldDescriptor& field,
                          Message& message, Setter<T> set, Setter<T> add) {
  T v = 0;
  if (absl::Status s = ParseInteger(dotted, value, field, v); !s.ok()) return s;
  return Store(field, message, v, set, add);
}

// Sets or appends `value` to the scalar `field` of `message`.
absl::Status SetScalar(absl::string_view dotted, absl::string_view value, const FieldDescriptor& field,
                       Message& message) {
  switch (field.cpp_type()) {
    case FieldDescriptor::CPPTYPE_INT32:
      return StoreInteger<int32_t>(dotted, value, field, message, &Reflection::SetInt32, &Reflection::AddInt32);
    case FieldDescriptor::CPPTYPE_INT64:
      return StoreInteger<int64_t>(dotted, value, field, message, &Reflection::SetInt64, &Reflection::AddInt64);
    case FieldDescriptor::CPPTYPE_UINT32:
      return StoreInteger<uint32_t>(dotted, value, field, message, &Reflection::SetUInt32, &Reflection::AddUInt32);
    case FieldDescriptor::CPPTYPE_UINT64:
      return StoreInteger<uint64_t>(dotted, value, field, message, &Reflection::SetUInt64, &Reflection::AddUInt64);
    case FieldDescriptor::CPPTYPE_DOUBLE:
    case FieldDescriptor::CPPTYPE_FLOAT: {
      double v = 0;
      if (absl::Status s = ParseDouble(dotted, value, v); !s.ok()) return s;
      if (field.cpp_type() == FieldDescriptor::CPPTYPE_DOUBLE) {
        return Store<double>(field, message, v, &Reflection::SetDouble, &Reflection::AddDouble);
      }
      return Store<float>(field, message, static_cast<float>(v), &Reflection::SetFloat, &Reflection::AddFloat);
    }
    case FieldDescriptor::CPPTYPE_BOOL: {
      const std::string lower = absl::AsciiStrToLower(value);
      if (lower != "true" && lower != "false" && lower != "1" && lower != "0") {
        return Bad(dotted, "not a bool (true, false, 1 or 0)", value);
      }
      return Store<bool>(field, message, lower == "true" || lower == "1", &Reflection::SetBool, &Reflection::AddBool);
    }
    case FieldDescriptor::CPPTYPE_ENUM: {
      auto e = ParseEnum(dotted, value, field);
      if (!e.ok()) return e.status();
      return Store<const EnumValueDescriptor*>(field, message, *e, &Reflection::SetEnum, &Reflection::AddEnum);
    }
    case FieldDescriptor::CPPTYPE_STRING:  // bytes too: the value's bytes as they are
      return Store<std::string>(field, message, std::string(value), &Reflection::SetString, &Reflection::AddString);
    case FieldDescriptor::CPPTYPE_MESSAGE:
      break;
  }
  return absl::InvalidArgumentError(
      absl::StrCat("query parameter ", dotted, ": is a message; name one of its fields (", dotted, ".x)"));
}

// The message holding the field `dotted` names (intermediate messages created) and the field.
absl::StatusOr<std::pair<Message*, const FieldDescriptor*>> Resolve(absl::string_view dotted, Message& message) {
  std::vector<absl::string_view> names = absl::StrSplit(dotted, '.');
  Message* current = &message;
  for (size_t i = 0;; ++i) {
    const auto* descriptor = current->GetDescriptor();
    const FieldDescriptor* field = descriptor->FindFieldByName(std::string(names[i]));
    if (field == nullptr) field = descriptor->FindFieldByCamelcaseName(std::string(names[i]));  // as JSON bodies
    if (field == nullptr) return absl::InvalidArgumentError(absl::StrCat("unknown query parameter: ", dotted));
    if (i + 1 == names.size()) return std::make_pair(current, field);
    if (field->cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE || field->is_repeated()) {
      return absl::InvalidArgumentError(absl::StrCat("unknown query parameter: ", dotted, " (", names[i],
                                                     " has no fields)"));
    }
    current = current->GetReflection()->MutableMessage(current, field);
  }
}

}  // namespace

absl::Status SetField(absl::string_view dotted, absl::string_view value, Message& message) {
  auto resolved = Resolve(dotted, message);
  if (!resolved.ok()) return resolved.status();
  return SetScalar(dotted, value, *resolved->second, *resolved->first);
}

absl::Status SetFieldsFromQuery(const std::multimap<std::string, std::string>& params, Message& message) {
  // A multimap keeps a repeated parameter's values in the order they came.
  for (auto it = params.begin(); it != params.end(); it = params.upper_bound(it->first)) {
    auto resolved = Resolve(it->first, message);
    if (!resolved.ok()) return resolved.status();
    const size_t count = params.count(it->first);
    if (count > 1 && !resolved->second->is_repeated()) {
      return absl::InvalidArgumentError(
          absl::StrCat("query parameter ", it->first, ": given ", count, " times but it is not repeated"));
    }
    for (auto value = it; value != params.end() && value->first == it->first; ++value) {
      if (absl::Status s = SetScalar(it->first, value->second, *resolved->second, *resolved->first); !s.ok()) return s;
    }
  }
  return absl::OkStatus();
}

}  // namespace fremen::server
