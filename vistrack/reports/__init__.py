"""``eval``'s files: tables, the HTML report and plots."""
