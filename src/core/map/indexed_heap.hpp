// A binary min-heap over vertex ids with a position index, so a vertex's key can change in place.
// Ties are broken by id, which makes every pop order deterministic.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

namespace toposimp::map {

class IndexedHeap {
public:
    static constexpr std::uint32_t kAbsent = std::numeric_limits<std::uint32_t>::max();

    explicit IndexedHeap(std::size_t capacity) : key_(capacity, 0.0), position_(capacity, kAbsent) {}

    bool empty() const { return heap_.empty(); }
    std::size_t size() const { return heap_.size(); }
    double top_key() const { return key_[heap_.front()]; }

    // Inserts id, or moves it to its new key if it is already queued.
    void set(std::uint32_t id, double key) {
        key_[id] = key;
        if (position_[id] == kAbsent) {
            position_[id] = static_cast<std::uint32_t>(heap_.size());
            heap_.push_back(id);
            sift_up(position_[id]);
        } else {
            sift_up(position_[id]);
            sift_down(position_[id]);
        }
    }

    std::uint32_t pop() {
        const std::uint32_t id = heap_.front();
        erase_at(0);
        return id;
    }

private:
    bool less(std::uint32_t a, std::uint32_t b) const {
        return key_[a] < key_[b] || (key_[a] == key_[b] && a < b);
    }

    void place(std::uint32_t slot, std::uint32_t id) {
        heap_[slot] = id;
        position_[id] = slot;
    }

    void erase_at(std::uint32_t slot) {
        position_[heap_[slot]] = kAbsent;
        const std::uint32_t last = heap_.back();
        heap_.pop_back();
        if (slot == heap_.size()) return;
        place(slot, last);
        sift_up(slot);
        sift_down(position_[last]);
    }

    void sift_up(std::uint32_t slot) {
        const std::uint32_t id = heap_[slot];
        while (slot > 0) {
            const std::uint32_t parent = (slot - 1) / 2;
            if (!less(id, heap_[parent])) break;
            place(slot, heap_[parent]);
            slot = parent;
        }
        place(slot, id);
    }

    void sift_down(std::uint32_t slot) {
        const std::uint32_t id = heap_[slot];
        const std::size_t size = heap_.size();
        for (;;) {
            std::size_t child = 2 * std::size_t{slot} + 1;
            if (child >= size) break;
            if (child + 1 < size && less(heap_[child + 1], heap_[child])) ++child;
            if (!less(heap_[child], id)) break;
            place(slot, heap_[child]);
            slot = static_cast<std::uint32_t>(child);
        }
        place(slot, id);
    }

    std::vector<double> key_;
    std::vector<std::uint32_t> position_;
    std::vector<std::uint32_t> heap_;
};

}  // namespace toposimp::map
