"""Night schedules: candidate epochs → blocks → sessions placed by priority."""
