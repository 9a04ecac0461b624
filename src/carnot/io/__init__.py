"""Files in and out: scenario files (format 1), result files (format 1), text tables.

The core never imports this package (DESIGN.md section 1)."""
