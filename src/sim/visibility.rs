//! Line of sight from the theodolite stations to a target through the arm's collision shapes.
