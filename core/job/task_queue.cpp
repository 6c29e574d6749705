// The job's task tree and the order its tasks are handed out in
// (schedule.hpp: task_tree, TaskQueue).
#include "tetiso/schedule.hpp"

namespace tetiso {

namespace {

// Appends a copy of the partition tree's subtree under `node`, in
// depth-first order; returns the copy's index.
int copy_subtree(const std::vector<DomainTreeNode>& partition_tree, int node, std::vector<TaskNode>& tree) {
    const DomainTreeNode& b = partition_tree[static_cast<std::size_t>(node)];
    const int at = static_cast<int>(tree.size());
    tree.push_back(TaskNode{b.first, b.count, -1, -1});
    if (b.left >= 0) {
        const int left = copy_subtree(partition_tree, b.left, tree);
        const int right = copy_subtree(partition_tree, b.right, tree);
        tree[static_cast<std::size_t>(at)].left = left;
        tree[static_cast<std::size_t>(at)].right = right;
    }
    return at;
}

} // namespace

std::vector<TaskNode> task_tree(const std::vector<DomainTreeNode>& partition_tree) {
    // The subtrees hanging off the partition tree's rightmost path, in
    // domain order: each left child on the path, then the node where the
    // chain ends. It ends at the first node of the path that covers at most
    // 1/kChainEnd of the domains, which joins the rest at the root as one
    // subtree: every seam of the chain joins the whole surface so far, and
    // a chain down to the last leaf made the job's last seconds nine seams
    // of the whole surface one after the other, each to add a few domains
    // (results/reduce-gpu/tail-seams).
    constexpr int kChainEnd = 8;
    const int domains = partition_tree[0].count;
    std::vector<int> hanging;
    int node = 0;
    while (partition_tree[static_cast<std::size_t>(node)].left >= 0 &&
           (node == 0 || kChainEnd * partition_tree[static_cast<std::size_t>(node)].count > domains)) {
        hanging.push_back(partition_tree[static_cast<std::size_t>(node)].left);
        node = partition_tree[static_cast<std::size_t>(node)].right;
    }
    hanging.push_back(node);

    // The chain's seams first, root at 0: seam k (k = 0 .. h-2, h subtrees)
    // joins the first h-1-k subtrees, seam k+1's piece, with subtree h-1-k.
    // Then the subtrees in domain order, so leaf tasks keep it too.
    const int seams = static_cast<int>(hanging.size()) - 1;
    std::vector<TaskNode> tree(static_cast<std::size_t>(seams));
    std::vector<int> subtree_root;
    for (const int h : hanging) subtree_root.push_back(copy_subtree(partition_tree, h, tree));
    for (int k = 0; k < seams; ++k) {
        const int joined = seams - k; // the subtree this seam adds
        const int rest = k + 1 < seams ? k + 1 : subtree_root[0];
        TaskNode& seam = tree[static_cast<std::size_t>(k)];
        seam.left = rest;
        seam.right = subtree_root[static_cast<std::size_t>(joined)];
        seam.first = 0;
        seam.count = tree[static_cast<std::size_t>(seam.right)].first + tree[static_cast<std::size_t>(seam.right)].count;
    }
    return tree;
}

TaskQueue::TaskQueue(const Job& job) {
    const int count = job.task_count();
    parent_.assign(static_cast<std::size_t>(count), -1);
    children_done_.assign(static_cast<std::size_t>(count), 0);
    for (int t = 0; t < count; ++t) {
        const TaskNode& n = job.node(t);
        if (n.left >= 0) {
            parent_[static_cast<std::size_t>(n.left)] = t;
            parent_[static_cast<std::size_t>(n.right)] = t;
        } else {
            // Leaf task indices follow domain ids (task_tree): ordering leaves
            // by task index orders them by domain.
            ready_.insert({1, t});
        }
    }
}

int TaskQueue::pop() {
    const int task = ready_.begin()->second;
    ready_.erase(ready_.begin());
    return task;
}

void TaskQueue::complete(int task) {
    const int parent = parent_[static_cast<std::size_t>(task)];
    if (parent < 0) {
        done_root_ = true;
        return;
    }
    if (++children_done_[static_cast<std::size_t>(parent)] == 2) ready_.insert({0, parent});
}

} // namespace tetiso
