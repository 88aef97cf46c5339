"""Film restoration: defects found and filled frame by frame, films in and out."""
