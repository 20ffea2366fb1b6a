#include "ordering.h"

#include <algorithm>

namespace timeopt::conic::internal {

std::vector<int> ReverseCuthillMcKee(int nodes, const std::vector<int>& adj_ptr, const std::vector<int>& adj) {
  std::vector<int> order;
  order.reserve(nodes);
  std::vector<char> placed(nodes, 0);
  std::vector<int> stamp(nodes, -1), queue(nodes), neighbours;
  int stamp_id = 0;
  auto degree = [&](int v) { return adj_ptr[v + 1] - adj_ptr[v]; };
  // Breadth-first levels from root; returns the eccentricity and leaves the last level in
  // queue[last_begin, last_end).
  int last_begin = 0, last_end = 0;
  auto levels = [&](int root) {
    const int id = stamp_id++;
    int head = 0, tail = 0, depth = 0;
    queue[tail++] = root;
    stamp[root] = id;
    while (head < tail) {
      const int level_end = tail;
      last_begin = head;
      last_end = level_end;
      for (; head < level_end; ++head) {
        const int v = queue[head];
        for (int q = adj_ptr[v]; q < adj_ptr[v + 1]; ++q) {
          const int u = adj[q];
          if (stamp[u] != id) {
            stamp[u] = id;
            queue[tail++] = u;
          }
        }
      }
      if (tail > level_end) ++depth;
    }
    return depth;
  };
  for (int start = 0; start < nodes; ++start) {
    if (placed[start]) continue;
    int root = start;
    int eccentricity = levels(root);
    for (int guard = 0; guard < 8; ++guard) {
      int candidate = queue[last_begin];
      for (int q = last_begin; q < last_end; ++q) {
        if (degree(queue[q]) < degree(candidate)) candidate = queue[q];
      }
      const int e = levels(candidate);
      if (e <= eccentricity) break;
      root = candidate;
      eccentricity = e;
    }
    const std::size_t begin = order.size();
    order.push_back(root);
    placed[root] = 1;
    for (std::size_t head = begin; head < order.size(); ++head) {
      const int v = order[head];
      neighbours.clear();
      for (int q = adj_ptr[v]; q < adj_ptr[v + 1]; ++q) {
        if (!placed[adj[q]]) {
          placed[adj[q]] = 1;
          neighbours.push_back(adj[q]);
        }
      }
      std::sort(neighbours.begin(), neighbours.end(),
                [&](int a, int b) { return degree(a) != degree(b) ? degree(a) < degree(b) : a < b; });
      order.insert(order.end(), neighbours.begin(), neighbours.end());
    }
  }
  std::reverse(order.begin(), order.end());
  return order;
}

}  // namespace timeopt::conic::internal
