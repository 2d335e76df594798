#include <visp3/hslam/vpHSlamException.h>

// Out of line so the vtable and type information live in the library: a vpHSlamException thrown here is caught
// by type in user code across the shared-library boundary (the module builds with hidden visibility).
vpHSlamException::vpHSlamException(ErrorCode code, const std::string &message)
    : vpException(static_cast<int>(code), message)
{
}

vpHSlamException::~vpHSlamException() = default;
