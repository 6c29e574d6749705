// An unstructured mesh split into domains by a domain id per tetrahedron
// (see mesh_partition.hpp): the shared edges, the merge tree, and each
// domain cut out of the whole mesh on demand.
#include "tetiso/mesh_partition.hpp"

#include <algorithm>
#include <limits>
#include <map>
#include <numeric>
#include <utility>

#include "merge_tree.hpp"
#include "table_file.hpp"
#include "tetiso/error.hpp"

#ifdef TETISO_HAVE_METIS
#include <metis.h>
#endif

namespace tetiso {
namespace {

constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

// METIS draws random numbers while it coarsens; a fixed seed makes its parts
// a function of the mesh alone.
constexpr int kMetisSeed = 20261123;

struct MergeNode {
    int left = -1, right = -1; // children, -1 for a leaf
    int part = -1;             // a leaf's source id
    std::int64_t tets = 0;     // in the whole subtree
    int lowest = 0;            // lowest source id in the subtree, to break ties
};

using detail::PairWeights;

// The merge tree over the source parts, bottom up by heavy-edge matching;
// the root is the last node.
std::vector<MergeNode> match_bottom_up(const std::vector<std::int64_t>& part_tets, const PairWeights& weights) {
    const int parts = static_cast<int>(part_tets.size());
    std::vector<MergeNode> nodes(static_cast<std::size_t>(parts));
    for (int p = 0; p < parts; ++p) nodes[static_cast<std::size_t>(p)] = MergeNode{-1, -1, p, part_tets[static_cast<std::size_t>(p)], p};
    std::vector<int> cluster_of(static_cast<std::size_t>(parts)); // node holding each part now
    std::iota(cluster_of.begin(), cluster_of.end(), 0);
    std::vector<int> active = cluster_of;
    const auto smaller = [&nodes](int a, int b) {
        const MergeNode& x = nodes[static_cast<std::size_t>(a)];
        const MergeNode& y = nodes[static_cast<std::size_t>(b)];
        return x.tets != y.tets ? x.tets < y.tets : x.lowest < y.lowest;
    };
    while (active.size() > 1) {
        std::map<int, std::vector<std::pair<int, std::int64_t>>> adjacent;
        {
            PairWeights between;
            for (const auto& [pq, weight] : weights) {
                const int a = cluster_of[static_cast<std::size_t>(pq.first)];
                const int b = cluster_of[static_cast<std::size_t>(pq.second)];
                if (a != b) between[std::minmax(a, b)] += weight;
            }
            for (const auto& [ab, weight] : between) {
                adjacent[ab.first].push_back({ab.second, weight});
                adjacent[ab.second].push_back({ab.first, weight});
            }
        }
        std::sort(active.begin(), active.end(), smaller);
        std::map<int, int> mate;
        for (const int c : active) {
            if (mate.count(c)) continue;
            int best = -1;
            std::int64_t best_weight = 0;
            for (const auto& [n, weight] : adjacent[c]) {
                if (mate.count(n)) continue;
                if (best < 0 || weight > best_weight || (weight == best_weight && smaller(n, best))) {
                    best = n;
                    best_weight = weight;
                }
            }
            if (best >= 0) {
                mate[c] = best;
                mate[best] = c;
            }
        }
        // Sets that share no edge with any other (a mesh of several
        // components): the two smallest join, so the tree still closes.
        if (mate.empty()) {
            mate[active[0]] = active[1];
            mate[active[1]] = active[0];
        }
        std::vector<int> redirect(nodes.size() + active.size());
        std::iota(redirect.begin(), redirect.end(), 0);
        std::vector<int> next;
        for (const int c : active) {
            const auto m = mate.find(c);
            if (m == mate.end()) {
                next.push_back(c);
                continue;
            }
            const int other = m->second;
            if (redirect[static_cast<std::size_t>(other)] != other) { // joined when its mate came up
                redirect[static_cast<std::size_t>(c)] = redirect[static_cast<std::size_t>(other)];
                continue;
            }
            const MergeNode& a = nodes[static_cast<std::size_t>(c)];
            const MergeNode& b = nodes[static_cast<std::size_t>(other)];
            MergeNode joined;
            joined.left = a.lowest < b.lowest ? c : other;
            joined.right = a.lowest < b.lowest ? other : c;
            joined.tets = a.tets + b.tets;
            joined.lowest = std::min(a.lowest, b.lowest);
            const int at = static_cast<int>(nodes.size());
            nodes.push_back(joined);
            redirect[static_cast<std::size_t>(c)] = at;
            next.push_back(at);
        }
        for (int& c : cluster_of) c = redirect[static_cast<std::size_t>(c)];
        active = std::move(next);
    }
    return nodes;
}

// Lays the merge tree out root first, children after their parent, and
// numbers the leaves in depth-first order (left first), which makes every
// node's domains a range. Appends each leaf's source id to `source_id`.
int lay_out(const std::vector<MergeNode>& nodes, int node, std::vector<DomainTreeNode>& tree,
            std::vector<int>& source_id) {
    const MergeNode& n = nodes[static_cast<std::size_t>(node)];
    const int at = static_cast<int>(tree.size());
    tree.push_back(DomainTreeNode{static_cast<int>(source_id.size()), 1, -1, -1});
    if (n.left < 0) {
        source_id.push_back(n.part);
        return at;
    }
    const int left = lay_out(nodes, n.left, tree, source_id);
    const int right = lay_out(nodes, n.right, tree, source_id);
    DomainTreeNode& t = tree[static_cast<std::size_t>(at)];
    t.left = left;
    t.right = right;
    t.count = static_cast<int>(source_id.size()) - t.first;
    return at;
}

} // namespace

void detail::build_merge_tree(const std::vector<std::int64_t>& part_tets, const PairWeights& weights,
                              std::vector<DomainTreeNode>& tree, std::vector<int>& source_id) {
    lay_out(match_bottom_up(part_tets, weights), 2 * static_cast<int>(part_tets.size()) - 2, tree, source_id);
}

void detail::group_shared_edges(const std::vector<std::pair<EdgeKey, int>>& holders, std::vector<EdgeKey>& keys,
                                std::vector<std::int64_t>& first, std::vector<int>& parts, PairWeights& weights) {
    first.push_back(0);
    for (std::size_t i = 0; i < holders.size();) {
        std::size_t j = i + 1;
        while (j < holders.size() && holders[j].first == holders[i].first) ++j;
        if (j - i > 1) {
            keys.push_back(holders[i].first);
            for (std::size_t a = i; a < j; ++a) {
                parts.push_back(holders[a].second);
                for (std::size_t b = a + 1; b < j; ++b) ++weights[{holders[a].second, holders[b].second}];
            }
            first.push_back(static_cast<std::int64_t>(parts.size()));
        }
        i = j;
    }
}

std::vector<std::vector<int>> detail::neighbour_lists(const PairWeights& weights, const std::vector<int>& domain_of_source) {
    std::vector<std::vector<int>> neighbours(domain_of_source.size());
    for (const auto& [pq, weight] : weights) {
        const int a = domain_of_source[static_cast<std::size_t>(pq.first)];
        const int b = domain_of_source[static_cast<std::size_t>(pq.second)];
        neighbours[static_cast<std::size_t>(a)].push_back(b);
        neighbours[static_cast<std::size_t>(b)].push_back(a);
    }
    for (auto& n : neighbours) std::sort(n.begin(), n.end());
    return neighbours;
}

namespace {

// Offsets of a counting sort: first[k] .. first[k + 1] for bucket k.
std::vector<std::int64_t> bucket_offsets(const std::vector<std::int64_t>& counts) {
    std::vector<std::int64_t> first(counts.size() + 1, 0);
    std::partial_sum(counts.begin(), counts.end(), first.begin() + 1);
    return first;
}

} // namespace

std::vector<std::int32_t> read_partition(const std::filesystem::path& file, std::size_t tet_count) {
    detail::TableFile table(file);
    std::vector<std::int32_t> part;
    part.reserve(tet_count);
    while (table.next()) {
        if (table.size() != 1)
            table.fail("the line holds " + std::to_string(table.size()) + " fields, not one domain id");
        const auto id = table.get<std::int64_t>(0, "domain id");
        if (id < 0 || id > std::numeric_limits<std::int32_t>::max())
            table.fail("domain id " + std::to_string(id) + " is outside [0, 2^31)");
        // Every domain holds a tetrahedron, so no id reaches the count.
        if (static_cast<std::uint64_t>(id) >= tet_count)
            table.fail("domain id " + std::to_string(id) + " for a mesh of " + std::to_string(tet_count) +
                       " tetrahedra: ids run from 0 without gaps, each domain holding one or more");
        if (part.size() == tet_count)
            table.fail("more domain ids than the mesh's " + std::to_string(tet_count) + " tetrahedra");
        part.push_back(static_cast<std::int32_t>(id));
    }
    if (part.size() != tet_count)
        throw Error(file.string() + ": " + std::to_string(part.size()) + " domain ids for the mesh's " +
                    std::to_string(tet_count) + " tetrahedra");
    return part;
}

bool have_metis() {
#ifdef TETISO_HAVE_METIS
    return true;
#else
    return false;
#endif
}

std::vector<std::int32_t> partition_with_metis(const Domain& mesh, int domains) {
    const std::size_t tets = mesh.tet_count();
    if (domains < 1) throw Error("domain count must be at least 1, got " + std::to_string(domains));
    if (static_cast<std::size_t>(domains) > tets)
        throw Error("cannot split " + std::to_string(tets) + " tetrahedra into " + std::to_string(domains) + " domains");
    if (domains == 1) return std::vector<std::int32_t>(tets, 0);
#ifdef TETISO_HAVE_METIS
    static_assert(sizeof(idx_t) >= sizeof(std::int32_t));
    idx_t element_count = static_cast<idx_t>(tets);
    idx_t node_count = static_cast<idx_t>(mesh.node_count());
    std::vector<idx_t> element_first(tets + 1);
    for (std::size_t t = 0; t <= tets; ++t) element_first[t] = static_cast<idx_t>(4 * t);
    std::vector<idx_t> element_nodes(mesh.tets.begin(), mesh.tets.end());
    idx_t common = 3; // tetrahedra are neighbours in the dual graph when they share a face
    idx_t parts = domains;
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = kMetisSeed;
    options[METIS_OPTION_NUMBERING] = 0;
    idx_t cut = 0;
    std::vector<idx_t> element_part(tets), node_part(mesh.node_count());
    const int status = METIS_PartMeshDual(&element_count, &node_count, element_first.data(), element_nodes.data(),
                                          nullptr, nullptr, &common, &parts, nullptr, options, &cut,
                                          element_part.data(), node_part.data());
    if (status != METIS_OK)
        throw Error("METIS could not split the mesh into " + std::to_string(domains) + " domains (status " +
                    std::to_string(status) + ")");
    std::vector<std::int32_t> part(element_part.begin(), element_part.end());
    std::vector<char> used(static_cast<std::size_t>(domains), 0);
    for (const std::int32_t p : part) used[static_cast<std::size_t>(p)] = 1;
    for (int p = 0; p < domains; ++p)
        if (!used[static_cast<std::size_t>(p)])
            throw Error("METIS left domain " + std::to_string(p) + " of " + std::to_string(domains) +
                        " empty: the mesh is too small for that many domains");
    return part;
#else
    throw Error("this tetiso was built without METIS: give each tetrahedron's domain in a partition file");
#endif
}

MeshPartition::MeshPartition(Domain mesh, const std::vector<std::int32_t>& part, std::string source)
    : mesh_(std::move(mesh)), source_(std::move(source)) {
    const std::size_t tets = mesh_.tet_count(), nodes = mesh_.node_count();
    if (tets == 0) throw Error(source_ + ": the mesh has no tetrahedra");
    if (part.size() != tets)
        throw Error(source_ + ": " + std::to_string(part.size()) + " domain ids for " + std::to_string(tets) +
                    " tetrahedra");
    for (std::size_t v = 0; v < nodes; ++v)
        if (mesh_.gid[v] != static_cast<GlobalId>(v)) throw Error(source_ + ": the mesh's global ids are not its node numbers");
    const auto [low, high] = std::minmax_element(part.begin(), part.end());
    if (*low < 0) throw Error(source_ + ": negative domain id " + std::to_string(*low));
    // Checked before a counter per id is allocated: ids run without gaps, so
    // the largest is below the tetrahedron count.
    if (static_cast<std::size_t>(*high) >= tets)
        throw Error(source_ + ": domain id " + std::to_string(*high) + " for " + std::to_string(tets) +
                    " tetrahedra (ids must run from 0 without gaps)");
    const int parts = *high + 1;
    std::vector<std::int64_t> part_tets(static_cast<std::size_t>(parts), 0);
    for (const std::int32_t p : part) ++part_tets[static_cast<std::size_t>(p)];
    for (int p = 0; p < parts; ++p)
        if (part_tets[static_cast<std::size_t>(p)] == 0)
            throw Error(source_ + ": domain " + std::to_string(p) + " has no tetrahedra (ids must run from 0 to " +
                        std::to_string(parts - 1) + " without gaps)");
    // Summed in file order, before the tetrahedra are regrouped: the spacing,
    // and with it the error bound, must not depend on the partition.
    spacing_ = mean_edge_length(mesh_);

    // Only an edge both of whose ends touch several domains can be shared.
    constexpr std::int32_t kSeveral = -2;
    std::vector<std::int32_t> node_part(nodes, -1);
    for (std::size_t t = 0; t < tets; ++t)
        for (int k = 0; k < 4; ++k) {
            std::int32_t& p = node_part[static_cast<std::size_t>(mesh_.tets[4 * t + static_cast<std::size_t>(k)])];
            p = p == -1 || p == part[t] ? part[t] : kSeveral;
        }
    std::vector<std::pair<EdgeKey, std::int32_t>> holders; // (edge, a domain holding it)
    for (std::size_t t = 0; t < tets; ++t)
        for (const auto& e : kTetEdges) {
            const auto a = mesh_.tets[4 * t + static_cast<std::size_t>(e[0])];
            const auto b = mesh_.tets[4 * t + static_cast<std::size_t>(e[1])];
            if (node_part[static_cast<std::size_t>(a)] == kSeveral && node_part[static_cast<std::size_t>(b)] == kSeveral)
                holders.push_back({edge_key(a, b), part[t]});
        }
    std::sort(holders.begin(), holders.end());
    holders.erase(std::unique(holders.begin(), holders.end()), holders.end());
    PairWeights weights;
    std::vector<int> shared_source; // each shared edge's domains, source ids
    detail::group_shared_edges(holders, shared_keys_, shared_first_, shared_source, weights);
    std::vector<std::pair<EdgeKey, std::int32_t>>().swap(holders);

    // The tree, and the domains renumbered in its leaf order.
    detail::build_merge_tree(part_tets, weights, tree_, source_id_);
    std::vector<int> domain_of_source(static_cast<std::size_t>(parts));
    for (int d = 0; d < parts; ++d) domain_of_source[static_cast<std::size_t>(source_id_[static_cast<std::size_t>(d)])] = d;
    const auto domain_of = [&](std::int32_t p) { return domain_of_source[static_cast<std::size_t>(p)]; };

    neighbours_ = detail::neighbour_lists(weights, domain_of_source);

    shared_domains_.resize(shared_source.size());
    std::vector<std::int64_t> shared_per_domain(static_cast<std::size_t>(parts), 0);
    for (std::size_t e = 0; e < shared_keys_.size(); ++e) {
        const auto first = shared_domains_.begin() + shared_first_[e];
        const auto last = shared_domains_.begin() + shared_first_[e + 1];
        std::transform(shared_source.begin() + shared_first_[e], shared_source.begin() + shared_first_[e + 1], first,
                       domain_of);
        std::sort(first, last);
        for (auto d = first; d != last; ++d) ++shared_per_domain[static_cast<std::size_t>(*d)];
    }
    // Each domain's shared edges: keys visited in order, so each list is sorted.
    domain_shared_first_ = bucket_offsets(shared_per_domain);
    domain_shared_.resize(shared_domains_.size());
    {
        std::vector<std::int64_t> fill(domain_shared_first_.begin(), domain_shared_first_.end() - 1);
        for (std::size_t e = 0; e < shared_keys_.size(); ++e)
            for (std::int64_t i = shared_first_[e]; i < shared_first_[e + 1]; ++i)
                domain_shared_[static_cast<std::size_t>(fill[static_cast<std::size_t>(shared_domains_[static_cast<std::size_t>(i)])]++)] =
                    shared_keys_[e];
    }

    // Tetrahedra grouped by domain, file order kept within each.
    std::vector<std::int64_t> domain_tets(static_cast<std::size_t>(parts));
    for (int p = 0; p < parts; ++p) domain_tets[static_cast<std::size_t>(domain_of(p))] = part_tets[static_cast<std::size_t>(p)];
    tets_first_ = bucket_offsets(domain_tets);
    {
        std::vector<std::int32_t> grouped(mesh_.tets.size());
        std::vector<std::int64_t> fill(tets_first_.begin(), tets_first_.end() - 1);
        for (std::size_t t = 0; t < tets; ++t) {
            const auto at = static_cast<std::size_t>(fill[static_cast<std::size_t>(domain_of(part[t]))]++);
            std::copy_n(mesh_.tets.begin() + static_cast<std::ptrdiff_t>(4 * t), 4,
                        grouped.begin() + static_cast<std::ptrdiff_t>(4 * at));
        }
        mesh_.tets = std::move(grouped);
    }

    std::vector<std::int64_t> per_node(nodes, 0);
    for (const std::int32_t v : mesh_.tets) ++per_node[static_cast<std::size_t>(v)];
    node_tets_first_ = bucket_offsets(per_node);
    node_tets_.resize(mesh_.tets.size());
    {
        std::vector<std::int64_t> fill(node_tets_first_.begin(), node_tets_first_.end() - 1);
        for (std::size_t i = 0; i < mesh_.tets.size(); ++i)
            node_tets_[static_cast<std::size_t>(fill[static_cast<std::size_t>(mesh_.tets[i])]++)] =
                static_cast<std::int32_t>(i / 4);
    }

    fingerprint_ = Digest()
                       .add(nodes)
                       .add(tets)
                       .add(mesh_.tets.data(), mesh_.tets.size())
                       .add(source_id_.data(), source_id_.size())
                       .add(mesh_.f.data(), mesh_.f.size())
                       .value();
}

std::unique_ptr<MeshPartition> partition_mesh(const MeshSource& source, const std::filesystem::path& partition_file,
                                              int domains) {
    if (mesh_format(source.path) == MeshFormat::pvtu && partition_file.empty() && domains == 0) {
        std::vector<std::int32_t> piece_of_tet;
        Domain mesh = read_mesh(source, &piece_of_tet);
        return std::make_unique<MeshPartition>(std::move(mesh), piece_of_tet, source.path.string() + "'s pieces");
    }
    Domain mesh = read_mesh(source);
    if (!partition_file.empty()) {
        std::vector<std::int32_t> part = read_partition(partition_file, mesh.tet_count());
        auto partition = std::make_unique<MeshPartition>(std::move(mesh), part, partition_file.string());
        if (domains != 0 && domains != partition->domain_count())
            throw Error(partition_file.string() + ": " + std::to_string(partition->domain_count()) +
                        " domains, where " + std::to_string(domains) + " were asked for");
        return partition;
    }
    if (domains < 1) throw Error("domain count must be at least 1, got " + std::to_string(domains));
    std::vector<std::int32_t> part = partition_with_metis(mesh, domains);
    return std::make_unique<MeshPartition>(std::move(mesh), part,
                                           domains == 1 ? std::string("the whole mesh") : std::string("METIS"));
}

std::int64_t MeshPartition::domain_tet_count(int domain) const {
    const auto d = static_cast<std::size_t>(domain);
    return tets_first_.at(d + 1) - tets_first_.at(d);
}

std::string MeshPartition::domain_name(int domain) const {
    return "domain " + std::to_string(domain) + " (domain " + std::to_string(source_id(domain)) + " of " + source_ + ")";
}

std::vector<int> MeshPartition::domains_of_edge(GlobalId a, GlobalId b) const {
    const EdgeKey key = edge_key(a, b);
    const auto found = std::lower_bound(shared_keys_.begin(), shared_keys_.end(), key);
    if (found != shared_keys_.end() && *found == key) {
        const auto e = static_cast<std::size_t>(found - shared_keys_.begin());
        return {shared_domains_.begin() + shared_first_[e], shared_domains_.begin() + shared_first_[e + 1]};
    }
    const auto nodes = static_cast<GlobalId>(mesh_.node_count());
    if (a < 0 || b < 0 || a >= nodes || b >= nodes || a == b) return {};
    // Held by one domain at most: any tetrahedron around the edge tells which.
    for (std::int64_t i = node_tets_first_[static_cast<std::size_t>(a)]; i < node_tets_first_[static_cast<std::size_t>(a) + 1]; ++i) {
        const auto t = static_cast<std::size_t>(node_tets_[static_cast<std::size_t>(i)]);
        const auto corners = mesh_.tets.begin() + static_cast<std::ptrdiff_t>(4 * t);
        if (std::find(corners, corners + 4, static_cast<std::int32_t>(b)) != corners + 4) {
            const auto holder = std::upper_bound(tets_first_.begin(), tets_first_.end(), static_cast<std::int64_t>(t));
            return {static_cast<int>(holder - tets_first_.begin()) - 1};
        }
    }
    return {};
}

Domain MeshPartition::make_domain(int domain) const {
    if (domain < 0 || domain >= domain_count())
        throw Error("no domain " + std::to_string(domain) + " in a partition of " + std::to_string(domain_count()));
    const auto d = static_cast<std::size_t>(domain);
    const auto corners = mesh_.tets.begin() + static_cast<std::ptrdiff_t>(4 * tets_first_[d]);
    const auto corners_end = mesh_.tets.begin() + static_cast<std::ptrdiff_t>(4 * tets_first_[d + 1]);
    // Local nodes in global order, so the domain's vertices come out in key order.
    std::vector<std::int32_t> global(corners, corners_end);
    std::sort(global.begin(), global.end());
    global.erase(std::unique(global.begin(), global.end()), global.end());
    const auto local = [&global](GlobalId v) {
        return static_cast<std::int32_t>(std::lower_bound(global.begin(), global.end(), v) - global.begin());
    };

    Domain out;
    out.id = domain;
    const std::size_t n = global.size();
    out.x.resize(n);
    out.y.resize(n);
    out.z.resize(n);
    out.f.resize(n);
    out.gid.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto v = static_cast<std::size_t>(global[i]);
        out.x[i] = mesh_.x[v];
        out.y[i] = mesh_.y[v];
        out.z[i] = mesh_.z[v];
        out.f[i] = mesh_.f[v];
        out.gid[i] = global[i];
    }
    out.tets.resize(static_cast<std::size_t>(corners_end - corners));
    std::transform(corners, corners_end, out.tets.begin(), local);
    out.shared_edges.assign(domain_shared_.begin() + domain_shared_first_[d],
                            domain_shared_.begin() + domain_shared_first_[d + 1]);
    out.interface.assign(n, 0);
    for (const EdgeKey key : out.shared_edges) {
        out.interface[static_cast<std::size_t>(local(edge_key_low(key)))] = 1;
        out.interface[static_cast<std::size_t>(local(edge_key_high(key)))] = 1;
    }
    return out;
}

} // namespace tetiso
