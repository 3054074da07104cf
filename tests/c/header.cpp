// tagsplat.h compiled as C++17 (scripts/test_c.sh: `c++ -std=c++17 -Wall -Wextra -Werror`) and
// linked against the static library: the header's declarations are C++-clean and extern "C",
// and libtagsplat_c.a links on its own.
#include "tagsplat.h"

#include <cstdio>
#include <cstring>

int main() {
    tagsplat_sequence *sequence = nullptr;
    tagsplat_status status = tagsplat_sequence_read(nullptr, &sequence);
    char message[256];
    tagsplat_last_error(message, sizeof message);
    bool ok = std::strcmp(tagsplat_version(), TAGSPLAT_VERSION_STRING) == 0 &&
              status == TAGSPLAT_STATUS_BAD_INPUT && sequence == nullptr &&
              std::strstr(message, "path is NULL") != nullptr;
    std::printf("C++17 header check: %s (%s)\n", ok ? "ok" : "FAILED", message);
    return ok ? 0 : 1;
}
