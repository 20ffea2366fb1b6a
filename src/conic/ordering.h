#pragma once
// Bandwidth-reducing ordering of the reduced KKT system (private to the conic module).

#include <vector>

namespace timeopt::conic::internal {

// Reverse Cuthill-McKee order of an undirected graph in adjacency-list (CSR) form: order[k] is the
// node placed k-th. Every connected component starts from a pseudo-peripheral node (George and Liu),
// and neighbours are visited by increasing degree, which gives a small bandwidth on path-like graphs.
std::vector<int> ReverseCuthillMcKee(int nodes, const std::vector<int>& adj_ptr, const std::vector<int>& adj);

}  // namespace timeopt::conic::internal
