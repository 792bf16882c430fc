"""rbm_nb.core"""
