// Flags whose values are an enum's names: each value is checked against the
// names the enum's to_string gives (so --help lists them and CLI11 refuses
// any other with the valid names) and stored as the enum, parsed once here.
#pragma once

#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

namespace odotune::cli {

template <class E>
std::vector<std::pair<std::string, E>> enum_names(std::initializer_list<E> values) {
  std::vector<std::pair<std::string, E>> names;
  for (E v : values) names.emplace_back(std::string(to_string(v)), v);  // to_string found by ADL
  return names;
}

namespace choices_detail {

template <class E>
E lookup(const std::vector<std::pair<std::string, E>>& names, const std::string& text) {
  for (const auto& [name, value] : names)
    if (name == text) return value;
  return names.front().second;  // not reached: IsMember checked the name
}

template <class E>
std::vector<std::string> keys(const std::vector<std::pair<std::string, E>>& names) {
  std::vector<std::string> k;
  for (const auto& n : names) k.push_back(n.first);
  return k;
}

template <class E>
void store(E& out, E value) {
  out = value;
}
template <class E>
void store(std::optional<E>& out, E value) {
  out = value;
}

}  // namespace choices_detail

// `out` is E or std::optional<E>.
template <class Out, class E>
CLI::Option* add_enum_option(CLI::App* app, const std::string& flag, Out& out, std::initializer_list<E> values,
                             const std::string& help) {
  const auto names = enum_names(values);
  return app
      ->add_option_function<std::string>(
          flag,
          [&out, names](const std::string& s) { choices_detail::store(out, choices_detail::lookup(names, s)); },
          help)
      ->check(CLI::IsMember(choices_detail::keys(names)));
}

// A comma-separated list of names into a vector.
template <class E>
CLI::Option* add_enum_list_option(CLI::App* app, const std::string& flag, std::vector<E>& out,
                                  std::initializer_list<E> values, const std::string& help) {
  const auto names = enum_names(values);
  return app
      ->add_option_function<std::vector<std::string>>(
          flag,
          [&out, names](const std::vector<std::string>& v) {
            out.clear();
            for (const std::string& s : v) out.push_back(choices_detail::lookup(names, s));
          },
          help)
      ->delimiter(',')
      ->check(CLI::IsMember(choices_detail::keys(names)));
}

}  // namespace odotune::cli
