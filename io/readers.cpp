// Placeholder replaced by the readers helper.
