// The job's task tree (task_tree): which pieces are seamed together, fixed
// before the job starts, so that the result does not depend on timing.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "tetiso/lattice.hpp"
#include "tetiso/schedule.hpp"

namespace tetiso {
namespace {

bool adjacent(const Decomposition& decomposition, const TaskNode& a, const TaskNode& b) {
    for (int d = a.first; d < a.first + a.count; ++d)
        for (const int n : decomposition.neighbours(d))
            if (n >= b.first && n < b.first + b.count) return true;
    return false;
}

// Lattice sizes and domain counts: one domain, two, odd and prime counts,
// and the paper's three series.
struct Case {
    int lattice, domains;
};
const Case kCases[] = {{6, 1}, {6, 2}, {9, 7}, {20, 63}, {20, 125}, {25, 250}, {30, 97}};

TEST(TaskTree, EveryDomainOnceAndEverySeamJoinsAdjacentNeighbours) {
    for (const Case c : kCases) {
        SCOPED_TRACE("N = " + std::to_string(c.lattice) + ", D = " + std::to_string(c.domains));
        const Lattice lattice(c.lattice);
        const Decomposition decomposition(lattice, c.domains);
        const std::vector<TaskNode> tree = task_tree(decomposition.tree());
        ASSERT_EQ(tree.size(), static_cast<std::size_t>(2 * c.domains - 1));
        EXPECT_EQ(tree[0].first, 0);
        EXPECT_EQ(tree[0].count, c.domains);
        std::vector<int> leaf_of(static_cast<std::size_t>(c.domains), -1);
        std::vector<int> parents(tree.size(), 0);
        for (std::size_t t = 0; t < tree.size(); ++t) {
            const TaskNode& n = tree[t];
            if (n.left < 0) {
                ASSERT_EQ(n.count, 1);
                ASSERT_EQ(n.right, -1);
                EXPECT_EQ(leaf_of[static_cast<std::size_t>(n.first)], -1) << "domain " << n.first << " twice";
                leaf_of[static_cast<std::size_t>(n.first)] = static_cast<int>(t);
                continue;
            }
            ASSERT_GT(n.left, static_cast<int>(t)); // children after their parent
            ASSERT_GT(n.right, static_cast<int>(t));
            const TaskNode& l = tree[static_cast<std::size_t>(n.left)];
            const TaskNode& r = tree[static_cast<std::size_t>(n.right)];
            ++parents[static_cast<std::size_t>(n.left)];
            ++parents[static_cast<std::size_t>(n.right)];
            EXPECT_EQ(l.first, n.first);
            EXPECT_EQ(r.first, l.first + l.count);
            EXPECT_EQ(l.count + r.count, n.count);
            EXPECT_TRUE(adjacent(decomposition, l, r)) << "seam task " << t << " joins pieces that share no edge";
        }
        EXPECT_EQ(parents[0], 0);
        for (std::size_t t = 1; t < tree.size(); ++t) EXPECT_EQ(parents[t], 1) << "task " << t;
        // Leaf tasks in domain order: the queue hands out the lowest first.
        for (int d = 0; d < c.domains; ++d) ASSERT_GE(leaf_of[static_cast<std::size_t>(d)], 0);
        EXPECT_TRUE(std::is_sorted(leaf_of.begin(), leaf_of.end()));
    }
}

// What the chain is for: the last domains handed out join everything else
// at the root as one subtree, the first node of the bisection tree's
// rightmost path that covers at most an eighth of the domains (or its last
// leaf); every other task is a node of the bisection tree, unchanged, or a
// seam of the chain, which adds one such subtree to all the domains before
// it (so it covers domains 0 .. k).
TEST(TaskTree, TheLastDomainsJoinAtTheRootAndTheRestIsBisectionSubtrees) {
    for (const Case c : kCases) {
        if (c.domains < 2) continue;
        SCOPED_TRACE("N = " + std::to_string(c.lattice) + ", D = " + std::to_string(c.domains));
        const Lattice lattice(c.lattice);
        const Decomposition decomposition(lattice, c.domains);
        const std::vector<TaskNode> tree = task_tree(decomposition.tree());
        const TaskNode& last = tree[static_cast<std::size_t>(tree[0].right)];
        EXPECT_EQ(last.first + last.count, c.domains);
        EXPECT_TRUE(last.count == 1 || 8 * last.count <= c.domains) << last.count << " domains join at the root";
        // The first such node: the path's node above it covers more (or is
        // the root).
        for (const DomainTreeNode& b : decomposition.tree())
            if (b.right >= 0 && decomposition.tree()[static_cast<std::size_t>(b.right)].first == last.first &&
                decomposition.tree()[static_cast<std::size_t>(b.right)].count == last.count) {
                EXPECT_TRUE(b.count == c.domains || 8 * b.count > c.domains) << "the chain stopped below " << b.count;
            }
        const auto& bisection = decomposition.tree();
        int chain = 0;
        for (std::size_t t = 0; t < tree.size(); ++t) {
            const TaskNode& n = tree[t];
            const auto same = [&](const DomainTreeNode& b) { return b.first == n.first && b.count == n.count; };
            if (std::any_of(bisection.begin(), bisection.end(), same)) continue;
            EXPECT_EQ(n.first, 0) << "task " << t << " is neither a bisection node nor on the chain";
            ++chain;
        }
        // Past two domains the root's other child is a seam of the chain.
        if (c.domains > 2) {
            EXPECT_GE(chain, 1);
        }
    }
}

} // namespace
} // namespace tetiso
