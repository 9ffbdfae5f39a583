// The one exception type for errors a user can act on: the message names the file and the field.
#pragma once

#include <stdexcept>
#include <string>

namespace npt {

class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace npt
