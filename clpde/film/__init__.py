"""Film restoration: defect detection, temporal fill, films in and out, long films."""
