"""Kind crank_rocker: synthesis of a crank-rocker from K, rocker swing and minimum transmission angle."""
