// Ranks simulated by threads, for the partitions whose ranks pool their
// scans (RankGroup): each thread builds the partition with its share, and
// all_gather pools the shares behind a barrier.
#pragma once

#include <barrier>
#include <cstddef>
#include <string>
#include <vector>

#include "tetiso/partition.hpp"

namespace tetiso {

class ThreadRanks {
public:
    explicit ThreadRanks(int size) : shares_(static_cast<std::size_t>(size)), barrier_(size) {}
    RankGroup group(int rank) {
        RankGroup group;
        group.rank = rank;
        group.size = static_cast<int>(shares_.size());
        group.all_gather = [this, rank](const std::string& mine) {
            shares_[static_cast<std::size_t>(rank)] = mine;
            barrier_.arrive_and_wait();
            std::vector<std::string> all = shares_;
            barrier_.arrive_and_wait();
            return all;
        };
        return group;
    }

private:
    std::vector<std::string> shares_;
    std::barrier<> barrier_;
};

} // namespace tetiso
