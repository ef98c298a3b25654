"""Brooks GPL (Guidance Programming Language) front end and interpreter."""
