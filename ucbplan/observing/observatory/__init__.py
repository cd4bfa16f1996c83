"""Where and when: sites, their sky, barycentric time, the run's time axis, semesters."""
