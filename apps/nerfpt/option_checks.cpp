#include "option_checks.h"

#include <cmath>
#include <cstdlib>
#include <string>

namespace npt::cli {
namespace {

// Decimal digits from `from` on, without a leading zero (CLI11 reads "010" as octal 8, "0x10" as 16).
bool decimal_digits(const std::string& s, size_t from) {
    if (s.size() <= from || (s[from] == '0' && s.size() > from + 1)) return false;
    for (size_t i = from; i < s.size(); ++i)
        if (s[i] < '0' || s[i] > '9') return false;
    return true;
}

// The value type CLI11 derived from the option's variable ("FLOAT", "INT", "UINT", "TEXT", ...), without the
// descriptions of validators that get_type_name() appends after a ':'.
std::string value_type(const CLI::Option* opt) {
    const std::string t = opt->get_type_name();
    return t.substr(0, t.find(':'));
}

const CLI::Validator k_finite(
    [](std::string& text) {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size()) return "'" + text + "' is not a number";
        if (!std::isfinite(v)) return "'" + text + "' is not a finite number";
        return std::string();
    },
    "");
const CLI::Validator k_integer(
    [](std::string& text) {
        if (decimal_digits(text, text.rfind('-', 0) == 0 ? 1 : 0)) return std::string();
        return "'" + text + "' is not a whole number in decimal digits (no leading zero)";
    },
    "");
const CLI::Validator k_unsigned(
    [](std::string& text) {
        if (decimal_digits(text, 0)) return std::string();
        return "'" + text + "' is not a whole number >= 0 in decimal digits (no leading zero)";
    },
    "");

}  // namespace

void check_numbers_strictly(CLI::App& app) {
    for (CLI::Option* opt : app.get_options()) {
        const std::string type = value_type(opt);
        if (type == "FLOAT") opt->check(k_finite);
        if (type == "INT") opt->check(k_integer);
        if (type == "UINT") opt->check(k_unsigned);
    }
    for (CLI::App* sub : app.get_subcommands({})) check_numbers_strictly(*sub);
}

}  // namespace npt::cli
