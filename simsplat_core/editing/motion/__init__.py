"""The motion controller of edited and inserted agents: requests, routes, speed profiles and the plans of the edit
ops."""
