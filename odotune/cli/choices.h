// Flags whose value is one of a type's names: an enum's, or another value
// type's with a to_string (objectives::TunedModel). The names are those
// to_string gives, over the type's list of values (its kAll… array), so
// --help shows them as the flag's type ("TEXT:{diagonal,blocks}") and any
// other value is refused in one line naming the flag, the value and the
// valid names:
//
//   odotune: --space 'block': expected diagonal or blocks (see --help)
//
// The value is parsed here, once: what the command puts in its request is
// the type, never the text.
#pragma once

#include <iterator>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <odotune/core/enum_names.h>

namespace odotune::cli {

// A parse that takes more than the names, e.g. an alias
// (calibration::parse_calibration_method's "batch").
template <class T>
using ParseName = bool (*)(std::string_view, T*);

// The type --help shows for a choice: "TEXT:{a,b,c}".
template <class T>
std::string choice_type_name(const std::vector<T>& values) {
  std::string names;
  for (const T& v : values) names += (names.empty() ? "" : ",") + std::string(to_string(v));
  return "TEXT:{" + names + "}";
}

// `text` as a value of `values` (by `parse` when given); throws CLI11's
// ValidationError with the one line above otherwise. For an option function
// that needs more than the value (cmd_calibrate.cpp's --method).
template <class T>
T parse_choice(const std::string& flag, const std::string& text, const std::vector<T>& values,
               ParseName<T> parse = nullptr) {
  T value = values.front();
  if (parse ? parse(text, &value) : core::parse_by_name(text, values, &value)) return value;
  throw CLI::ValidationError(fmt::format("{} '{}': expected {}", flag, text, core::names_or(values)));
}

namespace choices_detail {
template <class Values>
using ValueOf = std::decay_t<decltype(*std::begin(std::declval<const Values&>()))>;
}  // namespace choices_detail

// The flag's value, parsed, handed to `set` (called once with a T).
template <class Values, class Set>
CLI::Option* add_choice_option(CLI::App* app, const std::string& flag, Set set, const Values& values,
                               const std::string& help,
                               ParseName<choices_detail::ValueOf<Values>> parse = nullptr) {
  using T = choices_detail::ValueOf<Values>;
  std::vector<T> all(std::begin(values), std::end(values));
  const std::string type = choice_type_name(all);
  return app
      ->add_option_function<std::string>(
          flag,
          [flag, set = std::move(set), all = std::move(all), parse](const std::string& text) {
            set(parse_choice(flag, text, all, parse));
          },
          help)
      ->type_name(type);
}

// The same into `out`, a T or a std::optional<T> (not given: left as it is).
template <class Out, class Values>
CLI::Option* add_enum_option(CLI::App* app, const std::string& flag, Out& out, const Values& values,
                             const std::string& help,
                             ParseName<choices_detail::ValueOf<Values>> parse = nullptr) {
  return add_choice_option(
      app, flag, [&out](const choices_detail::ValueOf<Values>& v) { out = v; }, values, help, parse);
}
template <class Out, class E>
CLI::Option* add_enum_option(CLI::App* app, const std::string& flag, Out& out, std::initializer_list<E> values,
                             const std::string& help) {
  return add_enum_option(app, flag, out, std::vector<E>(values), help);
}

// A comma-separated list of names into a vector.
template <class E>
CLI::Option* add_enum_list_option(CLI::App* app, const std::string& flag, std::vector<E>& out,
                                  std::initializer_list<E> values, const std::string& help) {
  std::vector<E> all(values);
  const std::string type = choice_type_name(all);
  return app
      ->add_option_function<std::vector<std::string>>(
          flag,
          [&out, flag, all](const std::vector<std::string>& v) {
            out.clear();
            for (const std::string& s : v) out.push_back(parse_choice<E>(flag, s, all));
          },
          help)
      ->delimiter(',')
      ->type_name(type);
}

}  // namespace odotune::cli
