// SPDX-License-Identifier: MIT
#include "boxtree/version.h"

namespace boxtree {

const char* library_version() { return BOXTREE_VERSION_STRING; }

}  // namespace boxtree
