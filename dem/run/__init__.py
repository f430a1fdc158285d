"""`dem run` and what it needs: the runner, replicas, the plan and the stiffness rule, progress."""
