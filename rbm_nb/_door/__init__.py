"""rbm_nb._door"""
