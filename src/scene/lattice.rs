//! Lattice builders: the jelly cube and the cloth (to be written).
