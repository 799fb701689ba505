// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The slots of a sparse grid's chunks: a chunk gets the next slot when it is first added, so slots
// index dense per-chunk storage kept beside the index.

#include "core/hash.h"

#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace texfab::synthesis {

class ChunkIndex {
public:
  size_t size() const { return keys_.size(); }
  /// The chunks' keys, by slot.
  const std::vector<GridKey>& keys() const { return keys_; }
  /// The chunk's slot, or -1 when it has none.
  int32_t find(const GridKey& k) const {
    const auto it = slots_.find(k);
    return it == slots_.end() ? -1 : int32_t(it->second);
  }
  /// The chunk's slot, and whether this call added it.
  std::pair<uint32_t, bool> insert(const GridKey& k) {
    const auto [it, added] = slots_.try_emplace(k, uint32_t(keys_.size()));
    if (added) keys_.push_back(k);
    return {it->second, added};
  }

private:
  std::unordered_map<GridKey, uint32_t, GridKeyHash> slots_;
  std::vector<GridKey> keys_;
};

} // namespace texfab::synthesis
