"""sim_node, and a simulated flight replayed onto the graph for tests (flight_replay)."""
